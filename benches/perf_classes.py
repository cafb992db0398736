#!/usr/bin/env python3
"""Where the machine's CPU went during a recorded run, by what the kernel or the program was
doing: each sample of a `perf record -a -g` file is put in the first class whose key names
a frame of its call chain (the network namespace's set-up and clean-up, RCU grace
periods, seccomp, mounts, forks, execs, page faults, ...), else in "other". Prints the
samples of each class, and with --by-command the same for each command.

    perf record -a -g -F 2999 -e cpu-clock -o full.data -- \
        target/release/mazearena tournament --bots bots/c --mazes DIR --jobs 2 --sandbox full
    python3 benches/perf_classes.py full.data [--by-command]

A sample stands for 1/F of a second of one core (F: perf's -F): the difference of two
runs' classes, over the matches played, is what each class costs a match."""
import collections
import subprocess
import sys

CLASSES = [
    ("netns make", ["copy_net_ns", "setup_net"]),
    ("netns cleanup", ["cleanup_net", "inet_twsk_purge", "default_device_exit"]),
    ("rcu", ["rcu_exp", "synchronize_rcu", "rcu_do_batch", "rcu_core"]),
    ("seccomp attach", ["do_seccomp", "seccomp_set_mode_filter", "bpf_prog_create", "do_jit",
                        "bpf_convert_filter", "seccomp_cache_prepare"]),
    ("seccomp run", ["__seccomp_filter", "seccomp_run_filters"]),
    ("landlock", ["landlock"]),
    ("mount", ["do_mount", "path_mount", "__x64_sys_mount", "do_move_mount", "__x64_sys_fsmount",
               "__x64_sys_fsconfig", "__x64_sys_open_tree", "__x64_sys_umount", "mount_setattr"]),
    ("namespaces at exit", ["exit_task_namespaces", "put_mnt_ns", "free_nsproxy",
                            "zap_pid_ns_processes"]),
    ("clone/fork", ["copy_process", "kernel_clone"]),
    ("exec", ["bprm_execve", "do_execveat_common", "load_elf_binary"]),
    ("exit mm", ["exit_mmap", "mmput"]),
    ("proc", ["proc_"]),
    ("cgroup", ["cgroup"]),
    ("page fault", ["exc_page_fault", "asm_exc_page_fault"]),
    ("pipe", ["pipe_read", "pipe_write", "anon_pipe"]),
    ("epoll", ["ep_poll", "do_epoll"]),
    ("sched and idle", ["schedule", "finish_task_switch", "pv_native_safe_halt", "default_idle"]),
]


def classify(frames):
    for name, keys in CLASSES:
        if any(k in f for f in frames for k in keys):
            return name
    return "other"


def main():
    data, by_command = sys.argv[1], "--by-command" in sys.argv[2:]
    counts, per_command = collections.Counter(), collections.Counter()
    script = subprocess.Popen(["perf", "script", "-i", data, "-F", "comm,ip,sym"],
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    command, frames = None, []

    def flush():
        if command is not None:
            c = classify(frames)
            counts[c] += 1
            per_command[("kworker" if command.startswith("kworker") else command, c)] += 1

    for line in script.stdout:
        if not line.strip():
            flush()
            command, frames = None, []
        elif not line[0].isspace():
            flush()
            command, frames = line.split()[0], []
        else:
            parts = line.split(None, 1)
            frames.append(parts[1].strip() if len(parts) > 1 else "")
    flush()
    print(f"{sum(counts.values())} samples")
    for name, n in counts.most_common():
        print(f"{n:7d}  {name}")
    if by_command:
        print()
        for (cmd, name), n in per_command.most_common(60):
            print(f"{n:7d}  {cmd:20s} {name}")


if __name__ == "__main__":
    main()
