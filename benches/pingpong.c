/* The floor of one referee-bot exchange: two processes pass one short line each way
 * through a pair of pipes, ROUNDS times, and the mean round trip is printed in
 * microseconds. With "same" both are pinned to one core (as mazearena pins a match);
 * with "split" to two different cores.
 *   pingpong same|split [ROUNDS]                                                   */
#define _GNU_SOURCE
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static void pin(int core) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(core, &set);
    if (sched_setaffinity(0, sizeof set, &set) != 0) { perror("sched_setaffinity"); exit(1); }
}

static void exchange(int in, int out, const char *msg, size_t len, char *buf) {
    if (write(out, msg, len) != (ssize_t)len) { perror("write"); exit(1); }
    size_t got = 0;
    while (got == 0 || buf[got - 1] != '\n') {
        ssize_t n = read(in, buf + got, 256 - got);
        if (n <= 0) { perror("read"); exit(1); }
        got += (size_t)n;
    }
}

int main(int argc, char **argv) {
    int split = argc > 1 && strcmp(argv[1], "split") == 0;
    int rounds = argc > 2 ? atoi(argv[2]) : 20000;
    int to_child[2], to_parent[2];
    if (pipe(to_child) || pipe(to_parent)) { perror("pipe"); return 1; }
    const char *sense = "{\"type\":\"sense\",\"step\":1,\"sensors\":[0,11,0]}\n";
    const char *answer = "{\"rotation\":0,\"movement\":0}\n";
    char buf[256];
    pid_t child = fork();
    if (child == 0) {
        pin(split ? 1 : 0);
        for (int i = 0; i < rounds; i++) {
            size_t got = 0;
            while (got == 0 || buf[got - 1] != '\n') {
                ssize_t n = read(to_child[0], buf + got, sizeof buf - got);
                if (n <= 0) return 1;
                got += (size_t)n;
            }
            if (write(to_parent[1], answer, strlen(answer)) < 0) return 1;
        }
        return 0;
    }
    pin(0);
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    for (int i = 0; i < rounds; i++) exchange(to_parent[0], to_child[1], sense, strlen(sense), buf);
    clock_gettime(CLOCK_MONOTONIC, &b);
    waitpid(child, NULL, 0);
    double us = ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / 1e3 / rounds;
    printf("%.2f\n", us);
    return 0;
}
