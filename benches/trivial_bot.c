/* The cheapest possible protocol-v1 bot, to measure the referee's own per-step cost.
 *
 *   trivial_bot                 answers every sense with {"rotation":0,"movement":0}
 *                               (the match runs all 1000 steps);
 *   trivial_bot SCRIPT IDLE     answers IDLE senses that way, then the lines of the file
 *                               SCRIPT in turn (e.g. the optimal path, a reset, the path
 *                               again: the match finishes), then idles again.
 *
 * With IDLE > 2 it also clocks the idle steps from the inside: when it leaves them it
 * writes `idle_step_ns N` to stderr, N being the mean time from one sense to the next over
 * the idle steps after the first (a whole step: its answer, the referee's work, the next
 * sense), on CLOCK_MONOTONIC. The match's start and end are not in it.
 *
 * It exits on the end message. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static long long now_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (long long)t.tv_sec * 1000000000LL + t.tv_nsec;
}

int main(int argc, char **argv) {
    static char line[70000];
    static char script[4096][64];
    int lines = 0, next = 0;
    long idle = 0, senses = 0;
    long long first = 0;
    if (argc == 3) {
        FILE *f = fopen(argv[1], "r");
        if (!f) { perror(argv[1]); return 1; }
        while (lines < 4096 && fgets(script[lines], sizeof script[0], f)) lines++;
        fclose(f);
        idle = atol(argv[2]);
    }
    setvbuf(stdout, NULL, _IOLBF, 0);
    while (fgets(line, sizeof line, stdin)) {
        if (strstr(line, "\"type\":\"sense\"")) {
            senses++;
            if (senses == 2) first = now_ns();
            if (lines > 0 && idle == 0 && next == 0 && senses > 3) {
                fprintf(stderr, "idle_step_ns %lld\n", (now_ns() - first) / (senses - 2));
            }
            if (idle > 0 || next >= lines) {
                idle--;
                fputs("{\"rotation\":0,\"movement\":0}\n", stdout);
            } else {
                fputs(script[next++], stdout);
            }
        } else if (strstr(line, "\"type\":\"end\"")) {
            break;
        }
    }
    return 0;
}
