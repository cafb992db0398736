/*
 * mazebot.h: the protocol side of a mazearena bot written in C.
 *
 * The server talks to a bot through line-delimited JSON on stdin/stdout
 * (docs/PROTOCOL.md). This helper does all of it, so that a bot is three
 * callbacks and a call to mb_run():
 *
 *     #include "mazebot.h"
 *
 *     static mb_answer next_move(void *user, const int sensors[3], int run, int step)
 *     {
 *         (void)user; (void)run; (void)step;
 *         if (sensors[1] > 0)
 *             return mb_move(0, 1);        // straight on, one cell
 *         return mb_move(90, 0);           // turn right on the spot
 *     }
 *
 *     int main(void)
 *     {
 *         mb_bot bot = { .next_move = next_move };
 *         return mb_run(&bot);
 *     }
 *
 * The callbacks:
 *
 *   start(user, info)   optional; once, before the first move. info->maze_dim is
 *                       the side of the maze, info->seed is there so a randomized
 *                       bot can be made reproducible.
 *   next_move(user, sensors, run, step)
 *                       required; once per step. sensors = {left, front, right}:
 *                       open cells to the nearest wall, relative to the heading.
 *                       run is 0 (exploration) or 1 (timed run); step is the shared
 *                       1-based step counter. Return mb_move(rotation, movement)
 *                       (rotation -90, 0 or 90 degrees, clockwise positive, applied
 *                       first; movement -3..3 cells, negative = backward) or
 *                       mb_reset() (ends run 0; only accepted once the robot has
 *                       ended a move in the goal room during run 0).
 *   end(user, info)     optional; once, with the server's final message.
 *
 * Printing is safe: while mb_run is active, file descriptor 1 (printf, puts,
 * child processes) is a copy of stderr, which the server keeps as the bot's
 * log; protocol lines go through a private copy of the real stdout, and each
 * answer is flushed at once. fd 0 reads /dev/null, so nothing can eat the
 * server's messages by accident.
 *
 * Debug drawing (docs/PROTOCOL.md, "Debug drawing"): an answer may carry a
 * debug object that the replay viewer draws over the maze. Build it with an
 * mb_debug (below) and attach it to the answer:
 *
 *     static mb_debug dbg;                   // about 48 KiB: static, not on the stack
 *     mb_debug_clear(&dbg);
 *     mb_debug_text(&dbg, "run %d: %d steps to go", run, steps);
 *     mb_debug_wall(&dbg, 2, 3, MB_SIDE_RIGHT);
 *     mb_debug_grid(&dbg, n, dist, INF);     // dist[x * n + y]; INF shown as null
 *     return mb_with_debug(mb_move(0, 1), &dbg);
 *
 * Input lines may be up to MB_MAX_LINE bytes; the JSON is read by a small
 * hand-written parser that accepts any field order, any whitespace, unknown
 * fields (skipped, whatever their type) and a trailing "\r". Unknown message
 * types are ignored.
 */
#ifndef MAZEBOT_H
#define MAZEBOT_H

#ifdef __cplusplus
extern "C" {
#endif

/* Longest input line accepted, not counting the "\n" (the protocol's 64 KiB). */
#define MB_MAX_LINE 65536

/* One answer: a move, or a reset (then rotation and movement are ignored). */
typedef struct mb_answer {
    int rotation; /* -90, 0 or 90 */
    int movement; /* -3 .. 3 */
    int reset;    /* nonzero: {"reset":true} */
} mb_answer;

/* The start message. */
typedef struct mb_start_info {
    int protocol;                /* 1 */
    int maze_dim;                /* side of the maze, e.g. 12 */
    int max_steps;               /* 1000 */
    unsigned long long seed;     /* for reproducible randomness */
    int move_timeout_ms;         /* time per answer */
} mb_start_info;

/* The end message. Fields the server sent as null have has_... = 0. */
typedef struct mb_end_info {
    char status[32];  /* "finished", "step_limit", "timeout", "crashed", "protocol_error" */
    int has_score;
    double score;
    int has_run0_steps;
    long run0_steps;
    int has_run1_steps;
    long run1_steps;
} mb_end_info;

/* A bot: its callbacks and a pointer handed back to each of them. */
typedef struct mb_bot {
    void *user;
    void (*start)(void *user, const mb_start_info *info);                        /* optional */
    mb_answer (*next_move)(void *user, const int sensors[3], int run, int step); /* required */
    void (*end)(void *user, const mb_end_info *info);                            /* optional */
} mb_bot;

/* Answers for next_move. */
static inline mb_answer mb_move(int rotation, int movement)
{
    mb_answer a = {rotation, movement, 0};
    return a;
}

static inline mb_answer mb_reset(void)
{
    mb_answer a = {0, 0, 1};
    return a;
}

/* ------------------------------------------------------------------------ */
/* Debug drawing.                                                            */

/* The server keeps at most this many bytes of one step's debug JSON, and of a
 * whole match's. mb_run sends nothing beyond them (one line on stderr says so). */
#define MB_DEBUG_MAX (16 * 1024)
#define MB_DEBUG_MATCH_MAX (64 * 1024)

/* Wall sides, the same numbers as mazemap.h's MM_UP .. MM_LEFT. */
enum { MB_SIDE_UP, MB_SIDE_RIGHT, MB_SIDE_DOWN, MB_SIDE_LEFT };

/* The fields of a debug object, for mb_debug_empty. */
enum mb_debug_field {
    MB_DEBUG_TEXT = 1,
    MB_DEBUG_WALLS,
    MB_DEBUG_CELLS,
    MB_DEBUG_GRID,
    MB_DEBUG_COLORS,
    MB_DEBUG_PATH
};

/*
 * A debug object being built: what the bot believes, drawn by the replay viewer
 * at this step. (0, 0) is the bottom-left cell, x to the right, y up. Every
 * field is optional and sticky in the viewer (each shows the latest one sent),
 * so send big ones only when they change. The builder never writes out of its
 * buffers: an item that would take the object over MB_DEBUG_MAX bytes of JSON
 * is left out (the function returns -1 and `dropped` counts it). Strings are
 * escaped, and bytes that are not valid UTF-8 become U+FFFD, so the result is
 * always valid JSON. Declare it static or inside your (static) bot state.
 */
typedef struct mb_debug {
    char items[2 * MB_DEBUG_MAX]; /* each item: field tag, its JSON, NUL */
    unsigned long used;           /* bytes of items in use */
    unsigned long field_bytes[7]; /* JSON bytes of the live items of each field */
    int field_count[7];           /* live items of each field; -1: field absent */
    int dropped;                  /* items left out since mb_debug_clear */
    char json[MB_DEBUG_MAX + 1];  /* the object, written by mb_debug_json */
} mb_debug;

/* Empties d (call it at the start of every step). */
void mb_debug_clear(mb_debug *d);

/* A line of text shown with the step, printf-style (replaces an earlier one;
 * cut at 4 KiB). */
int mb_debug_text(mb_debug *d, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* A wall the bot believes in, on side MB_SIDE_UP .. MB_SIDE_LEFT of (x, y). */
int mb_debug_wall(mb_debug *d, int x, int y, int side);

/* A number, or a short text, written in cell (x, y). */
int mb_debug_cell_int(mb_debug *d, int x, int y, long value);
int mb_debug_cell_text(mb_debug *d, int x, int y, const char *text);

/* Values for the whole n x n maze: values[x * n + y] (the maze file's order);
 * a value equal to null_value is sent as null (nothing shown). Replaces an
 * earlier grid. */
int mb_debug_grid(mb_debug *d, int n, const int *values, int null_value);

/* A cell colour, "#rgb" or "#rrggbb" (anything else: -1, nothing added). */
int mb_debug_color(mb_debug *d, int x, int y, const char *hex);

/* A planned path through count cells, xy = {x0, y0, x1, y1, ...} (replaces an
 * earlier one; count 0 sends an empty path, which clears the drawn one). */
int mb_debug_path(mb_debug *d, int count, const int *xy);

/* Sends the field empty ("text": "", or an empty list): clears what the viewer
 * shows for it. */
int mb_debug_empty(mb_debug *d, enum mb_debug_field field);

/* The object's JSON (in d->json), or NULL when no field is set. */
const char *mb_debug_json(mb_debug *d);

/* Attaches d to answer a and returns a: `return mb_with_debug(mb_move(0, 1), &d);`.
 * d must stay untouched until next_move has returned (it is sent right after). */
mb_answer mb_with_debug(mb_answer a, mb_debug *d);

/* The same with a JSON object's text of your own (e.g. written by hand); mb_run
 * checks that it is one complete, valid JSON object in UTF-8 and otherwise
 * leaves it out, with a line on stderr. NULL: no debug object. */
mb_answer mb_with_debug_json(mb_answer a, const char *json);

/*
 * Plays one match over stdin/stdout. Returns 0 after the end message or when
 * stdin closes (or the server stops reading our answers); 1 after a message it
 * cannot use (a diagnostic is written to stderr), so `return mb_run(&bot);`
 * from main gives the right exit status.
 */
int mb_run(const mb_bot *bot);

/* The parser, exposed for tests: fills in the matching struct. */
enum mb_msg_type { MB_MSG_OTHER = 0, MB_MSG_START, MB_MSG_SENSE, MB_MSG_END };

typedef struct mb_message {
    enum mb_msg_type type;
    mb_start_info start;
    int sensors[3];
    int run;
    int step;
    mb_end_info end;
} mb_message;

/*
 * Parses one JSON line (len bytes, no "\n"). Returns 0 on success (type
 * MB_MSG_OTHER for a message type this helper does not know), or -1 with a
 * short reason in err (errlen bytes) when the line is not a JSON object or a
 * known message lacks a field it needs.
 */
int mb_parse_message(const char *line, unsigned long len, mb_message *msg, char *err,
                     unsigned long errlen);

#ifdef __cplusplus
}
#endif

#endif /* MAZEBOT_H */
