/* The floor of a referee's step: a referee that does nothing at each step but the
 * system calls a step needs, around the same bot as mazearena's benchmark
 * (benches/trivial_bot.c), so that the bot's own clock gives the per-step time of any
 * referee with the same duties. At each step it
 *   - writes the sense line (write),
 *   - waits until the bot's stdout or stderr holds bytes (epoll_wait on both: stderr
 *     written before an answer is read before it),
 *   - reads what is there (read; stderr first),
 *   - reads the bot's CPU time (the step's cpu_us): the CPU clock of the bot's process
 *     (clock_gettime), or with --cgroup the CPU counter of a cgroup the bot runs in
 *     (pread of cpuacct.usage, cgroup v1), as mazearena does without and with its
 *     sandbox.
 * No JSON, no game, no record: only the calls.
 *
 *   referee_floor [--cgroup] [--steps N] -- BOT [ARGS...]
 *
 * Both processes run on the core the referee was started on (mazearena pins a match to
 * one core). With --cgroup (root, cgroup v1) the bot is started in a new cgroup of the
 * cpuacct, memory, pids and cpuset hierarchies, which is removed at the end. BOT is run
 * from the current folder; whatever it writes to stderr (trivial_bot's idle_step_ns
 * line) is copied to ours. It sends N senses (default 905), then the end message. */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static const char *controllers[] = {"cpuacct", "memory", "pids", "cpuset"};
#define CONTROLLERS 4

static void die(const char *what) { perror(what); exit(1); }

static void write_file(const char *path, const char *text) {
    int fd = open(path, O_WRONLY);
    if (fd < 0 || write(fd, text, strlen(text)) != (ssize_t)strlen(text)) die(path);
    close(fd);
}

static void copy_file(const char *from, const char *to) {
    char buf[256];
    int fd = open(from, O_RDONLY);
    if (fd < 0) die(from);
    ssize_t n = read(fd, buf, sizeof buf - 1);
    if (n < 0) die(from);
    close(fd);
    buf[n] = 0;
    write_file(to, buf);
}

int main(int argc, char **argv) {
    int use_cgroup = 0, steps = 905, a = 1;
    for (; a < argc && strcmp(argv[a], "--") != 0; a++) {
        if (strcmp(argv[a], "--cgroup") == 0) use_cgroup = 1;
        else if (strcmp(argv[a], "--steps") == 0 && a + 1 < argc) steps = atoi(argv[++a]);
        else { fprintf(stderr, "usage: referee_floor [--cgroup] [--steps N] -- BOT [ARGS...]\n"); return 2; }
    }
    if (a + 1 >= argc) { fprintf(stderr, "referee_floor: no bot given\n"); return 2; }
    char **bot = argv + a + 1;

    int core = sched_getcpu();
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(core, &set);
    if (sched_setaffinity(0, sizeof set, &set) != 0) die("sched_setaffinity");

    char dirs[CONTROLLERS][256];
    if (use_cgroup) {
        for (int i = 0; i < CONTROLLERS; i++) {
            snprintf(dirs[i], sizeof dirs[i], "/sys/fs/cgroup/%s/mazearena-floor-%d", controllers[i], getpid());
            if (mkdir(dirs[i], 0755) != 0) die(dirs[i]);
        }
        char from[300], to[300], cpus[16];
        snprintf(from, sizeof from, "/sys/fs/cgroup/cpuset/cpuset.mems");
        snprintf(to, sizeof to, "%s/cpuset.mems", dirs[3]);
        copy_file(from, to);
        snprintf(to, sizeof to, "%s/cpuset.cpus", dirs[3]);
        snprintf(cpus, sizeof cpus, "%d", core);
        write_file(to, cpus);
    }

    int in[2], out[2], err[2];
    if (pipe2(in, O_CLOEXEC) || pipe2(out, O_CLOEXEC) || pipe2(err, O_CLOEXEC)) die("pipe2");
    pid_t pid = fork();
    if (pid < 0) die("fork");
    if (pid == 0) {
        if (use_cgroup) {
            char tasks[1100];
            for (int i = 0; i < CONTROLLERS; i++) {
                snprintf(tasks, sizeof tasks, "%s/tasks", dirs[i]);
                write_file(tasks, "0");
            }
        }
        dup2(in[0], 0);
        dup2(out[1], 1);
        dup2(err[1], 2);
        execvp(bot[0], bot);
        _exit(127);
    }
    close(in[0]);
    close(out[1]);
    close(err[1]);

    clockid_t clock;
    if (clock_getcpuclockid(pid, &clock) != 0) die("clock_getcpuclockid");
    int counter = -1;
    if (use_cgroup) {
        char path[300];
        snprintf(path, sizeof path, "%s/cpuacct.usage", dirs[0]);
        counter = open(path, O_RDONLY);
        if (counter < 0) die(path);
    }
    int ep = epoll_create1(EPOLL_CLOEXEC);
    struct epoll_event ev = {.events = EPOLLIN, .data.fd = err[0]};
    if (epoll_ctl(ep, EPOLL_CTL_ADD, err[0], &ev) != 0) die("epoll_ctl");
    ev.data.fd = out[0];
    if (epoll_ctl(ep, EPOLL_CTL_ADD, out[0], &ev) != 0) die("epoll_ctl");

    const char *start = "{\"type\":\"start\",\"protocol\":1,\"maze_dim\":16,\"max_steps\":1000,\"seed\":0,\"move_timeout_ms\":1000}\n";
    if (write(in[1], start, strlen(start)) < 0) die("write");
    char line[128], buf[4096], cpu_text[64];
    long long cpu_ns = 0;
    for (int step = 1; step <= steps; step++) {
        int n = snprintf(line, sizeof line, "{\"type\":\"sense\",\"run\":0,\"step\":%d,\"sensors\":[0,11,0]}\n", step);
        if (write(in[1], line, n) != n) die("write");
        int answered = 0;
        while (!answered) {
            struct epoll_event got[2];
            int k = epoll_wait(ep, got, 2, 10000);
            if (k <= 0) { fprintf(stderr, "referee_floor: no answer to step %d\n", step); return 1; }
            for (int i = 0; i < k; i++) if (got[i].data.fd == err[0]) {
                ssize_t m = read(err[0], buf, sizeof buf);
                if (m > 0) fwrite(buf, 1, m, stderr);
                else epoll_ctl(ep, EPOLL_CTL_DEL, err[0], NULL);
            }
            for (int i = 0; i < k; i++) if (got[i].data.fd == out[0]) {
                ssize_t m = read(out[0], buf, sizeof buf);
                if (m <= 0) { fprintf(stderr, "referee_floor: the bot ended at step %d\n", step); return 1; }
                answered = buf[m - 1] == '\n';
            }
        }
        if (use_cgroup) {
            ssize_t m = pread(counter, cpu_text, sizeof cpu_text - 1, 0);
            if (m <= 0) die("pread");
            cpu_text[m] = 0;
            cpu_ns = atoll(cpu_text);
        } else {
            struct timespec t;
            clock_gettime(clock, &t);
            cpu_ns = t.tv_sec * 1000000000LL + t.tv_nsec;
        }
    }
    const char *end = "{\"type\":\"end\",\"status\":\"step_limit\",\"score\":null,\"run0_steps\":null,\"run1_steps\":null}\n";
    if (write(in[1], end, strlen(end)) < 0) die("write");
    close(in[1]);
    ssize_t m;
    while ((m = read(err[0], buf, sizeof buf)) > 0) fwrite(buf, 1, m, stderr);
    int status;
    waitpid(pid, &status, 0);
    if (use_cgroup) {
        for (int i = 0; i < CONTROLLERS; i++) rmdir(dirs[i]);
    }
    (void)cpu_ns;
    return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? 0 : 1;
}
