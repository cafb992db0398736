/*
 * mazemap.h: the maze bookkeeping shared by the C bots (C11, libc only).
 *
 * A wall map of an n x n maze and the robot's pose, as the bots' sensors and
 * moves reveal them:
 *
 *   - cells are (x, y) with (0, 0) the start corner, x to the right, y up; the
 *     cell index is x * n + y (mm_cell);
 *   - directions are absolute: MM_UP (+y), MM_RIGHT (+x), MM_DOWN, MM_LEFT, in
 *     clockwise order, so (d + 1) & 3 turns right, (d + 3) & 3 left and
 *     (d + 2) & 3 is the opposite side; MM_DX / MM_DY step one cell;
 *   - every side of every cell is MM_UNKNOWN, MM_OPEN or MM_WALL, stored for both
 *     cells that share it (edges[cell * 4 + d]); the outer perimeter starts as
 *     wall (mm_map_init);
 *   - the goal room is the 2 x 2 block of cells mm_goal_lo(m) .. mm_goal_lo(m) + 1
 *     in x and y (n / 2 - 1 .. n / 2), tested by mm_in_goal.
 *
 * Strategies (flood fill, A*, route planning) stay in the bots; this file only
 * holds what each of them needs the same way.
 */
#ifndef MAZEMAP_H
#define MAZEMAP_H

#include "mazebot.h"

enum { MM_UP, MM_RIGHT, MM_DOWN, MM_LEFT };       /* absolute directions, clockwise */
enum { MM_UNKNOWN = 0, MM_OPEN = 1, MM_WALL = 2 }; /* what is known of an edge */

extern const int MM_DX[4]; /* {0, 1, 0, -1}: x step of each direction */
extern const int MM_DY[4]; /* {1, 0, -1, 0}: y step of each direction */

/* The wall map. n == 0 means no map (never initialised, or out of memory). */
typedef struct mm_map {
    int n;                /* side of the maze */
    unsigned char *edges; /* edges[mm_cell(x, y) * 4 + d]: MM_UNKNOWN, MM_OPEN or MM_WALL */
} mm_map;

/* Where the robot is: its cell and the absolute direction it faces. */
typedef struct mm_pose {
    int x, y, heading;
} mm_pose;

/* Allocates an all-unknown map of side n (n >= 1) with the perimeter set to wall.
 * Returns 1, or 0 (m->n = 0, m->edges = NULL) when out of memory. */
int mm_map_init(mm_map *m, int n);

/* Frees the map's memory and sets m->n = 0. */
void mm_map_free(mm_map *m);

/* 1 if (x, y) is a cell of the maze. */
static inline int mm_inside(const mm_map *m, int x, int y)
{
    return x >= 0 && y >= 0 && x < m->n && y < m->n;
}

/* The index of cell (x, y): x * n + y. */
static inline int mm_cell(const mm_map *m, int x, int y)
{
    return x * m->n + y;
}

/* What is known of side d of cell (x, y). */
static inline int mm_edge(const mm_map *m, int x, int y, int d)
{
    return m->edges[mm_cell(m, x, y) * 4 + d];
}

/* Sets side d of cell (x, y), and the same side seen from the neighbour beyond
 * it if that is inside the maze, to state. */
void mm_set_edge(mm_map *m, int x, int y, int d, int state);

/* The smallest x (and y) of the goal room: n / 2 - 1. */
static inline int mm_goal_lo(const mm_map *m)
{
    return m->n / 2 - 1;
}

/* 1 if (x, y) is one of the four goal-room cells. */
static inline int mm_in_goal(const mm_map *m, int x, int y)
{
    int lo = mm_goal_lo(m), hi = lo + 1;
    return x >= lo && x <= hi && y >= lo && y <= hi;
}

/* Records one sensor reading taken at pose p: sensors = {left, front, right},
 * each the number of open cells to the nearest wall. Along each ray the first
 * sensors[i] edges become open (stopping at the maze border), and the next one
 * a wall; a negative reading records nothing. */
void mm_sense(mm_map *m, const mm_pose *p, const int sensors[3]);

/* Dead reckoning: the pose after answer a (rotation first, then movement cells,
 * negative = backward). A reset answer leaves the pose unchanged. Exact as long
 * as the bot only moves across edges it knows to be open. */
void mm_apply(mm_pose *p, mb_answer a);

#endif /* MAZEMAP_H */
