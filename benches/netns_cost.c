/* What a network namespace of its own adds to a match: ROUNDS clones of a process that
 * exits at once, into new PID, mount and IPC namespaces (a warm match's before its own
 * network namespace) and into the same plus a new network namespace, taken in turn. Prints
 * the microseconds a clone and exit take, each way. Needs root.
 *
 *   cc -O2 -o netns_cost benches/netns_cost.c && ./netns_cost 2000 */
#define _GNU_SOURCE
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + t.tv_nsec / 1e9;
}

static double rounds_of(int n, int flags) {
    double t0 = now();
    for (int i = 0; i < n; i++) {
        long pid = syscall(SYS_clone, flags | SIGCHLD, 0, 0, 0, 0);
        if (pid == 0) _exit(0);
        if (pid < 0) { perror("clone"); exit(1); }
        int status;
        waitpid(pid, &status, 0);
    }
    return (now() - t0) / n * 1e6;
}

int main(int argc, char **argv) {
    int n = argc > 1 ? atoi(argv[1]) : 2000;
    int base = CLONE_NEWPID | CLONE_NEWNS | CLONE_NEWIPC;
    for (int r = 0; r < 3; r++) {
        double without = rounds_of(n, base);
        double with = rounds_of(n, base | CLONE_NEWNET);
        printf("round %d: %.0f us without a network namespace, %.0f us with one: %.0f us more\n",
               r + 1, without, with, with - without);
    }
    return 0;
}
