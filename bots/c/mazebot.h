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
