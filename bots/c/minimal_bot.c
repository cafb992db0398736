/*
 * minimal_bot: a small, deterministic reference bot for mazearena, in C.
 * The C twin of bots/python/simple_bot.py; the protocol is in mazebot.c, the
 * wall map and dead reckoning in mazemap.c.
 *
 * Strategy
 * --------
 * Wall map. Every edge between two cells is unknown, open or wall (the outer
 * perimeter starts as wall). A sensor reading d in a direction reveals the
 * edges along that ray: d open edges, then a wall.
 *
 * Run 0 (exploration). Flood fill from the goal room over every edge not known
 * to be a wall (unknown counts as open), so each cell gets an optimistic
 * distance to the goal. Each step the bot heads to a neighbour one closer,
 * preferring straight ahead, then left, right, back, and moves up to 3 cells
 * while the cells keep getting closer and the edges are known open (so it
 * never hits a wall and always knows where it is). It re-plans every step.
 * After a step that ended in the goal room it answers reset.
 *
 * Run 1 (timed run). Breadth-first search over (cell, heading) using only
 * edges known to be open (unknown = wall): one step is one rotation (-90, 0,
 * 90) followed by a straight move of -3..3 cells, exactly the game's move.
 * The bot follows the shortest such plan, re-planned every step.
 *
 * If the goal cannot be reached (the map proves it walled off), the bot turns
 * on the spot until the step limit: it never crashes and never hits a wall.
 *
 * Debug drawing: each answer carries an mb_debug for the replay viewer (the
 * flood-fill distances as a grid, the way down them to the goal as a path, a
 * line of text, and the walls it knows whenever it learnt a new one). It
 * changes nothing in the moves.
 */
#include "mazebot.h"
#include "mazemap.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define INF 0x3fffffff
#define MAX_DIM 1024 /* larger mazes: the bot only turns on the spot */

typedef struct bot {
    mm_map map;           /* walls; map.n = 0: unusable maze, only safe moves */
    int *dist;            /* flood fill */
    int *queue;           /* BFS queue: n*n*4 entries */
    int *parent;          /* run-1 BFS: parent state, or -1 */
    signed char *act;     /* run-1 BFS: action that led to the state, (rot index, movement) */
    mm_pose pose;         /* where the robot is (dead reckoning) */
    int run;
    int entered_goal;
    int flooded;          /* dist holds this step's flood fill (run 0) */
    int walls_drawn;      /* walls in the last debug drawing that listed them */
    int *path;            /* debug drawing: x, y of each cell of the path */
    mb_debug debug;       /* the debug drawing being built */
} bot_state;

/* --- run 0: flood fill, unknown = open ------------------------------------ */

static void flood(bot_state *b)
{
    const mm_map *map = &b->map;
    int head = 0, tail = 0, lo = mm_goal_lo(map);
    for (int i = 0; i < map->n * map->n; i++)
        b->dist[i] = INF;
    for (int gx = lo; gx <= lo + 1; gx++)
        for (int gy = lo; gy <= lo + 1; gy++) {
            if (!mm_inside(map, gx, gy))
                continue;
            b->dist[mm_cell(map, gx, gy)] = 0;
            b->queue[tail++] = mm_cell(map, gx, gy);
        }
    while (head < tail) {
        int c = b->queue[head++], x = c / map->n, y = c % map->n;
        for (int d = 0; d < 4; d++) {
            int nx = x + MM_DX[d], ny = y + MM_DY[d];
            if (mm_edge(map, x, y, d) == MM_WALL || !mm_inside(map, nx, ny))
                continue;
            if (b->dist[mm_cell(map, nx, ny)] == INF) {
                b->dist[mm_cell(map, nx, ny)] = b->dist[c] + 1;
                b->queue[tail++] = mm_cell(map, nx, ny);
            }
        }
    }
}

static mb_answer explore_move(bot_state *b)
{
    const mm_map *map = &b->map;
    static const int order[4] = {0, 3, 1, 2}; /* straight, left, right, back */
    int here, rel = -1, d = 0;

    flood(b);
    b->flooded = 1;
    here = b->dist[mm_cell(map, b->pose.x, b->pose.y)];
    if (here == INF)
        return mb_move(90, 0); /* the goal is walled off: turn on the spot */
    for (int i = 0; i < 4; i++) {
        int dd = (b->pose.heading + order[i]) & 3;
        int nx = b->pose.x + MM_DX[dd], ny = b->pose.y + MM_DY[dd];
        if (mm_edge(map, b->pose.x, b->pose.y, dd) != MM_WALL && mm_inside(map, nx, ny) &&
            b->dist[mm_cell(map, nx, ny)] == here - 1) {
            rel = order[i];
            d = dd;
            break;
        }
    }
    if (rel < 0) { /* in the goal room without having entered it (n = 2): step out */
        for (int dd = 0; dd < 4 && rel < 0; dd++)
            if (mm_edge(map, b->pose.x, b->pose.y, dd) == MM_OPEN) {
                rel = (dd - b->pose.heading + 4) & 3;
                d = dd;
            }
        if (rel < 0)
            return mb_move(90, 0); /* look around */
    }
    if (mm_edge(map, b->pose.x, b->pose.y, d) != MM_OPEN)
        return mb_move(90, 0); /* the edge behind is unsensed: turn to look at it */

    int rotation = rel == 1 ? 90 : rel == 3 ? -90 : 0;
    int sign = rel == 2 ? -1 : 1;
    int cells = 0, x = b->pose.x, y = b->pose.y;
    while (cells < 3 && mm_edge(map, x, y, d) == MM_OPEN) {
        int nx = x + MM_DX[d], ny = y + MM_DY[d];
        if (cells > 0 && b->dist[mm_cell(map, nx, ny)] != b->dist[mm_cell(map, x, y)] - 1)
            break;
        x = nx;
        y = ny;
        cells++;
        if (mm_in_goal(map, x, y))
            break;
    }
    return mb_move(rotation, sign * cells);
}

/* --- run 1: BFS over (cell, heading), unknown = wall ----------------------- */

static int plan_move(bot_state *b, mb_answer *out)
{
    const mm_map *map = &b->map;
    static const int rotations[3] = {0, -90, 90};
    static const int movements[7] = {3, 2, 1, -1, -2, -3, 0};
    int states = map->n * map->n * 4, head = 0, tail = 0;
    int start = mm_cell(map, b->pose.x, b->pose.y) * 4 + b->pose.heading;

    for (int i = 0; i < states; i++)
        b->parent[i] = -2; /* unvisited */
    b->parent[start] = -1;
    b->queue[tail++] = start;
    while (head < tail) {
        int s = b->queue[head++];
        int x0 = s / 4 / map->n, y0 = s / 4 % map->n, h0 = s % 4;
        for (int r = 0; r < 3; r++) {
            int h = (h0 + rotations[r] / 90 + 4) & 3;
            for (int m = 0; m < 7; m++) {
                int mv = movements[m], d = mv >= 0 ? h : (h + 2) & 3;
                int x = x0, y = y0, ok = 1;
                for (int k = 0; k < abs(mv); k++) {
                    if (mm_edge(map, x, y, d) != MM_OPEN ||
                        !mm_inside(map, x + MM_DX[d], y + MM_DY[d])) {
                        ok = 0;
                        break;
                    }
                    x += MM_DX[d];
                    y += MM_DY[d];
                }
                int t = mm_cell(map, x, y) * 4 + h;
                if (!ok || b->parent[t] != -2)
                    continue;
                b->parent[t] = s;
                b->act[t * 2] = (signed char)r;
                b->act[t * 2 + 1] = (signed char)mv;
                if (mm_in_goal(map, x, y)) { /* walk back to the first action of the plan */
                    while (b->parent[t] != start)
                        t = b->parent[t];
                    *out = mb_move(rotations[(int)b->act[t * 2]], b->act[t * 2 + 1]);
                    return 1;
                }
                b->queue[tail++] = t;
            }
        }
    }
    return 0;
}

/* --- debug drawing (the replay viewer's layer; no effect on the moves) ------- */

/* Builds b->debug for this step: text, the walls if they changed, and in run 0
 * the flood fill as a grid and the way down it from the robot's cell. */
static void draw(bot_state *b, const char *text)
{
    const mm_map *map = &b->map;
    int n = map->n, walls = 0;
    mb_debug *d = &b->debug;

    mb_debug_clear(d);
    mb_debug_text(d, "%s", text);
    for (int x = 0; x < n; x++)
        for (int y = 0; y < n; y++)
            walls += (y + 1 < n && mm_edge(map, x, y, MM_UP) == MM_WALL) +
                     (x + 1 < n && mm_edge(map, x, y, MM_RIGHT) == MM_WALL);
    if (walls != b->walls_drawn) { /* fields are sticky: send the walls when they change */
        b->walls_drawn = walls;
        mb_debug_empty(d, MB_DEBUG_WALLS); /* the field, even with no wall yet */
        for (int x = 0; x < n; x++)
            for (int y = 0; y < n; y++) {
                if (y + 1 < n && mm_edge(map, x, y, MM_UP) == MM_WALL)
                    mb_debug_wall(d, x, y, MB_SIDE_UP);
                if (x + 1 < n && mm_edge(map, x, y, MM_RIGHT) == MM_WALL)
                    mb_debug_wall(d, x, y, MB_SIDE_RIGHT);
            }
    }
    if (!b->flooded)
        return;
    mb_debug_grid(d, n, b->dist, INF);
    int count = 0, x = b->pose.x, y = b->pose.y;
    while (count < n * n && b->dist[mm_cell(map, x, y)] != INF) {
        int here = b->dist[mm_cell(map, x, y)], next = -1;
        b->path[2 * count] = x;
        b->path[2 * count + 1] = y;
        count++;
        for (int dd = 0; dd < 4 && here > 0 && next < 0; dd++) {
            int nx = x + MM_DX[dd], ny = y + MM_DY[dd];
            if (mm_edge(map, x, y, dd) != MM_WALL && mm_inside(map, nx, ny) &&
                b->dist[mm_cell(map, nx, ny)] == here - 1)
                next = dd;
        }
        if (next < 0)
            break;
        x += MM_DX[next];
        y += MM_DY[next];
    }
    mb_debug_path(d, count, b->path);
}

/* --- the bot interface ------------------------------------------------------ */

static void home(bot_state *b)
{
    b->pose.x = 0;
    b->pose.y = 0;
    b->pose.heading = MM_UP;
}

static void start(void *user, const mb_start_info *info)
{
    bot_state *b = user;
    int n = info->maze_dim;
    memset(b, 0, sizeof *b);
    b->walls_drawn = -1; /* the first drawing lists the walls, even none */
    if (n >= 2 && n <= MAX_DIM) {
        size_t cells = (size_t)n * (size_t)n;
        b->dist = malloc(cells * sizeof *b->dist);
        b->queue = malloc(cells * 4 * sizeof *b->queue);
        b->parent = malloc(cells * 4 * sizeof *b->parent);
        b->act = malloc(cells * 4 * 2);
        b->path = malloc(cells * 2 * sizeof *b->path);
        if (!(b->dist && b->queue && b->parent && b->act && b->path && mm_map_init(&b->map, n)))
            fprintf(stderr, "minimal_bot: out of memory for a %dx%d maze\n", n, n);
    } else {
        fprintf(stderr, "minimal_bot: cannot map a %dx%d maze; turning on the spot\n", n, n);
    }
    home(b);
}

static mb_answer next_move(void *user, const int sensors[3], int run, int step)
{
    bot_state *b = user;
    mb_answer a;
    (void)step;
    if (b->map.n == 0)
        return mb_move(90, 0);
    if (run != b->run) { /* the reset was accepted: back at the start */
        b->run = run;
        home(b);
    }
    mm_sense(&b->map, &b->pose, sensors);
    b->flooded = 0;
    if (run == 0 && b->entered_goal) {
        draw(b, "goal room entered: reset");
        mb_debug_empty(&b->debug, MB_DEBUG_GRID); /* clear the run-0 drawing */
        mb_debug_empty(&b->debug, MB_DEBUG_PATH);
        return mb_with_debug(mb_reset(), &b->debug);
    }
    if (run != 1 || !plan_move(b, &a))
        a = explore_move(b);
    draw(b, run == 1 ? "run 1: shortest known path" : "run 0: flood fill, unknown = open");
    mm_apply(&b->pose, a); /* exact: moves only cross edges known to be open */
    if (run == 0 && mm_in_goal(&b->map, b->pose.x, b->pose.y))
        b->entered_goal = 1;
    return mb_with_debug(a, &b->debug);
}

static void end(void *user, const mb_end_info *info)
{
    (void)user;
    fprintf(stderr, "minimal_bot: %s", info->status);
    if (info->has_score)
        fprintf(stderr, ", score %.3f", info->score);
    fprintf(stderr, "\n");
}

int main(void)
{
    static bot_state state;
    mb_bot bot = {&state, start, next_move, end};
    return mb_run(&bot);
}
