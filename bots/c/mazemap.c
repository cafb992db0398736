/* mazemap.c: the wall map and dead reckoning shared by the C bots; see mazemap.h. */
#include "mazemap.h"

#include <stdlib.h>

const int MM_DX[4] = {0, 1, 0, -1};
const int MM_DY[4] = {1, 0, -1, 0};

int mm_map_init(mm_map *m, int n)
{
    m->n = 0;
    m->edges = n >= 1 ? calloc((size_t)n * (size_t)n * 4, 1) : NULL;
    if (!m->edges)
        return 0;
    m->n = n;
    for (int i = 0; i < n; i++) {
        mm_set_edge(m, i, 0, MM_DOWN, MM_WALL);
        mm_set_edge(m, i, n - 1, MM_UP, MM_WALL);
        mm_set_edge(m, 0, i, MM_LEFT, MM_WALL);
        mm_set_edge(m, n - 1, i, MM_RIGHT, MM_WALL);
    }
    return 1;
}

void mm_map_free(mm_map *m)
{
    free(m->edges);
    m->edges = NULL;
    m->n = 0;
}

void mm_set_edge(mm_map *m, int x, int y, int d, int state)
{
    int nx = x + MM_DX[d], ny = y + MM_DY[d];
    m->edges[mm_cell(m, x, y) * 4 + d] = (unsigned char)state;
    if (mm_inside(m, nx, ny))
        m->edges[mm_cell(m, nx, ny) * 4 + ((d + 2) & 3)] = (unsigned char)state;
}

void mm_sense(mm_map *m, const mm_pose *p, const int sensors[3])
{
    for (int i = 0; i < 3; i++) {
        int d = (p->heading + i + 3) & 3; /* left, front, right */
        int x = p->x, y = p->y;
        for (int k = 0; k < sensors[i] && mm_inside(m, x + MM_DX[d], y + MM_DY[d]); k++) {
            mm_set_edge(m, x, y, d, MM_OPEN);
            x += MM_DX[d];
            y += MM_DY[d];
        }
        if (sensors[i] >= 0)
            mm_set_edge(m, x, y, d, MM_WALL);
    }
}

void mm_apply(mm_pose *p, mb_answer a)
{
    if (a.reset)
        return;
    p->heading = (p->heading + a.rotation / 90 + 4) & 3;
    int d = a.movement >= 0 ? p->heading : (p->heading + 2) & 3;
    p->x += MM_DX[d] * abs(a.movement);
    p->y += MM_DY[d] * abs(a.movement);
}
