/*
 * minimal_bot: a small, deterministic reference bot for mazearena, in C.
 * The C twin of bots/python/simple_bot.py; the protocol is in mazebot.c.
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
 */
#include "mazebot.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { UP, RIGHT, DOWN, LEFT };
enum { UNKNOWN = 0, OPEN = 1, WALL = 2 };
#define INF 0x3fffffff
#define MAX_DIM 1024 /* larger mazes: the bot only turns on the spot */

static const int DX[4] = {0, 1, 0, -1};
static const int DY[4] = {1, 0, -1, 0};

typedef struct bot {
    int n;                /* side of the maze; 0 = unusable maze, only safe moves */
    unsigned char *edges; /* edges[(x * n + y) * 4 + d] */
    int *dist;            /* flood fill */
    int *queue;           /* BFS queue: n*n*4 entries */
    int *parent;          /* run-1 BFS: parent state, or -1 */
    signed char *act;     /* run-1 BFS: action that led to the state, (rot index, movement) */
    int x, y, heading;
    int run;
    int entered_goal;
} bot_state;

/* --- map ----------------------------------------------------------------- */

static int inside(const bot_state *b, int x, int y)
{
    return x >= 0 && y >= 0 && x < b->n && y < b->n;
}

static int cell(const bot_state *b, int x, int y)
{
    return x * b->n + y;
}

static int edge(const bot_state *b, int x, int y, int d)
{
    return b->edges[cell(b, x, y) * 4 + d];
}

static void set_edge(bot_state *b, int x, int y, int d, int state)
{
    int nx = x + DX[d], ny = y + DY[d];
    b->edges[cell(b, x, y) * 4 + d] = (unsigned char)state;
    if (inside(b, nx, ny))
        b->edges[cell(b, nx, ny) * 4 + ((d + 2) & 3)] = (unsigned char)state;
}

static int in_goal(const bot_state *b, int x, int y)
{
    int lo = b->n / 2 - 1, hi = b->n / 2;
    return x >= lo && x <= hi && y >= lo && y <= hi;
}

static void sense(bot_state *b, const int sensors[3])
{
    for (int i = 0; i < 3; i++) {
        int d = (b->heading + i + 3) & 3; /* left, front, right */
        int x = b->x, y = b->y;
        for (int k = 0; k < sensors[i] && inside(b, x + DX[d], y + DY[d]); k++) {
            set_edge(b, x, y, d, OPEN);
            x += DX[d];
            y += DY[d];
        }
        if (sensors[i] >= 0)
            set_edge(b, x, y, d, WALL);
    }
}

/* --- run 0: flood fill, unknown = open ------------------------------------ */

static void flood(bot_state *b)
{
    int head = 0, tail = 0, lo = b->n / 2 - 1;
    for (int i = 0; i < b->n * b->n; i++)
        b->dist[i] = INF;
    for (int gx = lo; gx <= lo + 1; gx++)
        for (int gy = lo; gy <= lo + 1; gy++) {
            if (!inside(b, gx, gy))
                continue;
            b->dist[cell(b, gx, gy)] = 0;
            b->queue[tail++] = cell(b, gx, gy);
        }
    while (head < tail) {
        int c = b->queue[head++], x = c / b->n, y = c % b->n;
        for (int d = 0; d < 4; d++) {
            int nx = x + DX[d], ny = y + DY[d];
            if (edge(b, x, y, d) == WALL || !inside(b, nx, ny))
                continue;
            if (b->dist[cell(b, nx, ny)] == INF) {
                b->dist[cell(b, nx, ny)] = b->dist[c] + 1;
                b->queue[tail++] = cell(b, nx, ny);
            }
        }
    }
}

static mb_answer explore_move(bot_state *b)
{
    static const int order[4] = {0, 3, 1, 2}; /* straight, left, right, back */
    int here, rel = -1, d = 0;

    flood(b);
    here = b->dist[cell(b, b->x, b->y)];
    if (here == INF)
        return mb_move(90, 0); /* the goal is walled off: turn on the spot */
    for (int i = 0; i < 4; i++) {
        int dd = (b->heading + order[i]) & 3;
        int nx = b->x + DX[dd], ny = b->y + DY[dd];
        if (edge(b, b->x, b->y, dd) != WALL && inside(b, nx, ny) &&
            b->dist[cell(b, nx, ny)] == here - 1) {
            rel = order[i];
            d = dd;
            break;
        }
    }
    if (rel < 0) { /* in the goal room without having entered it (n = 2): step out */
        for (int dd = 0; dd < 4 && rel < 0; dd++)
            if (edge(b, b->x, b->y, dd) == OPEN) {
                rel = (dd - b->heading + 4) & 3;
                d = dd;
            }
        if (rel < 0)
            return mb_move(90, 0); /* look around */
    }
    if (edge(b, b->x, b->y, d) != OPEN)
        return mb_move(90, 0); /* the edge behind is unsensed: turn to look at it */

    int rotation = rel == 1 ? 90 : rel == 3 ? -90 : 0;
    int sign = rel == 2 ? -1 : 1;
    int cells = 0, x = b->x, y = b->y;
    while (cells < 3 && edge(b, x, y, d) == OPEN) {
        int nx = x + DX[d], ny = y + DY[d];
        if (cells > 0 && b->dist[cell(b, nx, ny)] != b->dist[cell(b, x, y)] - 1)
            break;
        x = nx;
        y = ny;
        cells++;
        if (in_goal(b, x, y))
            break;
    }
    return mb_move(rotation, sign * cells);
}

/* --- run 1: BFS over (cell, heading), unknown = wall ----------------------- */

static int plan_move(bot_state *b, mb_answer *out)
{
    static const int rotations[3] = {0, -90, 90};
    static const int movements[7] = {3, 2, 1, -1, -2, -3, 0};
    int states = b->n * b->n * 4, head = 0, tail = 0;
    int start = cell(b, b->x, b->y) * 4 + b->heading;

    for (int i = 0; i < states; i++)
        b->parent[i] = -2; /* unvisited */
    b->parent[start] = -1;
    b->queue[tail++] = start;
    while (head < tail) {
        int s = b->queue[head++];
        int x0 = s / 4 / b->n, y0 = s / 4 % b->n, h0 = s % 4;
        for (int r = 0; r < 3; r++) {
            int h = (h0 + rotations[r] / 90 + 4) & 3;
            for (int m = 0; m < 7; m++) {
                int mv = movements[m], d = mv >= 0 ? h : (h + 2) & 3;
                int x = x0, y = y0, ok = 1;
                for (int k = 0; k < abs(mv); k++) {
                    if (edge(b, x, y, d) != OPEN || !inside(b, x + DX[d], y + DY[d])) {
                        ok = 0;
                        break;
                    }
                    x += DX[d];
                    y += DY[d];
                }
                int t = cell(b, x, y) * 4 + h;
                if (!ok || b->parent[t] != -2)
                    continue;
                b->parent[t] = s;
                b->act[t * 2] = (signed char)r;
                b->act[t * 2 + 1] = (signed char)mv;
                if (in_goal(b, x, y)) { /* walk back to the first action of the plan */
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

/* --- the bot interface ------------------------------------------------------ */

static void home(bot_state *b)
{
    b->x = 0;
    b->y = 0;
    b->heading = UP;
}

static void start(void *user, const mb_start_info *info)
{
    bot_state *b = user;
    int n = info->maze_dim;
    memset(b, 0, sizeof *b);
    if (n >= 2 && n <= MAX_DIM) {
        size_t cells = (size_t)n * (size_t)n;
        b->edges = calloc(cells * 4, 1);
        b->dist = malloc(cells * sizeof *b->dist);
        b->queue = malloc(cells * 4 * sizeof *b->queue);
        b->parent = malloc(cells * 4 * sizeof *b->parent);
        b->act = malloc(cells * 4 * 2);
        if (b->edges && b->dist && b->queue && b->parent && b->act)
            b->n = n;
        else
            fprintf(stderr, "minimal_bot: out of memory for a %dx%d maze\n", n, n);
    } else {
        fprintf(stderr, "minimal_bot: cannot map a %dx%d maze; turning on the spot\n", n, n);
    }
    for (int i = 0; i < b->n; i++) {
        set_edge(b, i, 0, DOWN, WALL);
        set_edge(b, i, b->n - 1, UP, WALL);
        set_edge(b, 0, i, LEFT, WALL);
        set_edge(b, b->n - 1, i, RIGHT, WALL);
    }
    home(b);
}

static void apply(bot_state *b, mb_answer a)
{
    /* dead reckoning; exact because moves only cross edges known to be open */
    b->heading = (b->heading + a.rotation / 90 + 4) & 3;
    int d = a.movement >= 0 ? b->heading : (b->heading + 2) & 3;
    b->x += DX[d] * abs(a.movement);
    b->y += DY[d] * abs(a.movement);
}

static mb_answer next_move(void *user, const int sensors[3], int run, int step)
{
    bot_state *b = user;
    mb_answer a;
    (void)step;
    if (b->n == 0)
        return mb_move(90, 0);
    if (run != b->run) { /* the reset was accepted: back at the start */
        b->run = run;
        home(b);
    }
    sense(b, sensors);
    if (run == 0 && b->entered_goal)
        return mb_reset();
    if (run != 1 || !plan_move(b, &a))
        a = explore_move(b);
    apply(b, a);
    if (run == 0 && in_goal(b, b->x, b->y))
        b->entered_goal = 1;
    return a;
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
