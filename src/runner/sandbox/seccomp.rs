//! The seccomp filter a bot runs under: a deny list of system calls no bot needs
//! (debugging other processes, mounts, kernel keyrings, eBPF, perf, io_uring, new
//! namespaces, kernel modules...). Everything else is allowed, so every language
//! runtime works unchanged. Built with `seccompiler` (rust-vmm, Firecracker's filter
//! compiler); no C library is needed.

use std::collections::BTreeMap;

use seccompiler::{
    BpfProgram, SeccompAction, SeccompCmpArgLen, SeccompCmpOp, SeccompCondition, SeccompFilter,
    SeccompRule,
};

/// System calls refused with `EPERM` that no part of the sandbox itself makes either: a
/// warm sandbox's supervisor puts these on itself when it starts
/// ([`helper_filter`]), so its matches inherit them.
const DENIED_ALWAYS: &[i64] = &[
    libc::SYS_ptrace,
    libc::SYS_process_vm_readv,
    libc::SYS_process_vm_writev,
    libc::SYS_keyctl,
    libc::SYS_add_key,
    libc::SYS_request_key,
    libc::SYS_bpf,
    libc::SYS_perf_event_open,
    libc::SYS_io_uring_setup,
    libc::SYS_io_uring_enter,
    libc::SYS_io_uring_register,
    libc::SYS_userfaultfd,
    libc::SYS_open_by_handle_at,
    libc::SYS_name_to_handle_at,
    libc::SYS_kexec_load,
    libc::SYS_kexec_file_load,
    libc::SYS_init_module,
    libc::SYS_finit_module,
    libc::SYS_delete_module,
    libc::SYS_reboot,
    libc::SYS_swapon,
    libc::SYS_swapoff,
    libc::SYS_acct,
    libc::SYS_quotactl,
    libc::SYS_syslog,
    libc::SYS_settimeofday,
    libc::SYS_clock_settime,
    libc::SYS_adjtimex,
    libc::SYS_clock_adjtime,
    libc::SYS_fanotify_init,
    libc::SYS_lookup_dcookie,
    libc::SYS_personality,
    // Probes of the host's page cache, which every sandbox shares: whether a page of a
    // file is cached, without reading it (docs/SECURITY.md, "Page cache"). Linux AIO
    // goes too: its requests carry RWF_NOWAIT in memory the filter cannot read.
    libc::SYS_mincore,
    SYS_CACHESTAT,
    libc::SYS_io_setup,
    libc::SYS_io_submit,
];

/// `cachestat(2)` (Linux 6.5): the page-cache state of a range of a file. The same
/// number on every architecture.
const SYS_CACHESTAT: i64 = 451;

/// `RWF_NOWAIT`: a read or write that fails instead of waiting for the disk, so that a
/// read tells whether its pages were cached.
const RWF_NOWAIT: u64 = 0x8;

/// System calls refused with `EPERM` when their flags (argument `.1`) hold
/// `RWF_NOWAIT`: `preadv2` and `pwritev2` (flags are their sixth argument).
const NOWAIT_CALLS: &[(i64, u8)] = &[(libc::SYS_preadv2, 5), (libc::SYS_pwritev2, 5)];

/// System calls refused with `EPERM` that a warm match's init makes before its walls
/// (mounts; its supervisor's `clone` makes the namespaces): put on each match
/// ([`match_filters`]), with `clone`'s namespace flags.
const DENIED_PER_MATCH: &[i64] = &[
    libc::SYS_mount,
    libc::SYS_umount2,
    libc::SYS_pivot_root,
    libc::SYS_chroot,
    libc::SYS_move_mount,
    libc::SYS_open_tree,
    libc::SYS_fsopen,
    libc::SYS_fsmount,
    libc::SYS_fsconfig,
    libc::SYS_fspick,
    libc::SYS_mount_setattr,
    libc::SYS_unshare,
    libc::SYS_setns,
];

/// `clone` flags that make new namespaces: refused, as `unshare` is.
const NAMESPACE_FLAGS: &[u64] = &[
    libc::CLONE_NEWUSER as u64,
    libc::CLONE_NEWNS as u64,
    libc::CLONE_NEWPID as u64,
    libc::CLONE_NEWNET as u64,
    libc::CLONE_NEWIPC as u64,
    libc::CLONE_NEWUTS as u64,
    libc::CLONE_NEWCGROUP as u64,
];

/// Why a filter could not be built (a bug or an unsupported architecture).
#[derive(Debug, thiserror::Error)]
#[error("could not build the seccomp filter: {0}")]
pub struct FilterError(String);

fn arch() -> Result<seccompiler::TargetArch, FilterError> {
    std::env::consts::ARCH
        .try_into()
        .map_err(|e| FilterError(format!("{e:?}")))
}

/// The filters a one-shot sandbox's jail installs, in order: the whole deny list
/// (`EPERM`), then `x86_64_abi_and_clone3` (or its equivalent elsewhere).
///
/// The deny list refuses `DENIED_ALWAYS`, `DENIED_PER_MATCH` and `clone` with
/// namespace flags; `clone3` is answered `ENOSYS` so that C libraries fall back to `clone`,
/// whose flags the filter sees. On x86_64 the second filter also refuses (`EPERM`) every
/// system call made through the x32 ABI (numbers with [`X32_SYSCALL_BIT`]): the deny list
/// compares numbers, and on a kernel with x32 enabled the same calls have other numbers
/// there.
///
/// # Errors
/// [`FilterError`] on an architecture seccompiler does not know.
pub fn filters() -> Result<Vec<BpfProgram>, FilterError> {
    let all: Vec<i64> = DENIED_ALWAYS
        .iter()
        .chain(DENIED_PER_MATCH)
        .copied()
        .collect();
    Ok(vec![deny(&all, true, true)?, second()?])
}

/// What a warm sandbox's supervisor installs on itself when it starts, before it takes
/// any request: `DENIED_ALWAYS`. Every match's init, and so its bot, inherits it.
///
/// # Errors
/// [`FilterError`] on an architecture seccompiler does not know.
pub fn helper_filter() -> Result<BpfProgram, FilterError> {
    deny(DENIED_ALWAYS, false, true)
}

/// What a warm match's init installs behind its other walls, on top of the supervisor's
/// [`helper_filter`]: `DENIED_PER_MATCH` and `clone` with namespace flags, then the
/// second filter. Together the two refuse what [`filters`] refuses; the kernel prepares
/// its cache of allowed calls for each filter it attaches, and a shorter filter attached
/// per match costs less than the whole list (about 0.1 ms a match here).
///
/// # Errors
/// [`FilterError`] on an architecture seccompiler does not know.
pub fn match_filters() -> Result<Vec<BpfProgram>, FilterError> {
    Ok(vec![deny(DENIED_PER_MATCH, true, false)?, second()?])
}

/// A filter refusing `denied` with `EPERM` (and `clone` with namespace flags when
/// `clone_flags`, `preadv2`/`pwritev2` with `RWF_NOWAIT` when `nowait`); another
/// architecture is killed.
fn deny(denied: &[i64], clone_flags: bool, nowait: bool) -> Result<BpfProgram, FilterError> {
    let mut rules: BTreeMap<i64, Vec<SeccompRule>> =
        denied.iter().map(|&nr| (nr, Vec::new())).collect();
    if nowait {
        for &(nr, arg) in NOWAIT_CALLS {
            let rule = SeccompCondition::new(
                arg,
                SeccompCmpArgLen::Dword,
                SeccompCmpOp::MaskedEq(RWF_NOWAIT),
                RWF_NOWAIT,
            )
            .and_then(|c| SeccompRule::new(vec![c]))
            .map_err(|e| FilterError(e.to_string()))?;
            rules.insert(nr, vec![rule]);
        }
    }
    if clone_flags {
        let clone_rules = NAMESPACE_FLAGS
            .iter()
            .map(|&flag| {
                SeccompCondition::new(
                    0,
                    SeccompCmpArgLen::Qword,
                    SeccompCmpOp::MaskedEq(flag),
                    flag,
                )
                .and_then(|c| SeccompRule::new(vec![c]))
            })
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| FilterError(e.to_string()))?;
        rules.insert(libc::SYS_clone, clone_rules);
    }
    let filter = SeccompFilter::new(
        rules,
        SeccompAction::Allow,
        SeccompAction::Errno(libc::EPERM as u32),
        arch()?,
    )
    .map_err(|e| FilterError(e.to_string()))?;
    BpfProgram::try_from(filter).map_err(|e| FilterError(e.to_string()))
}

/// `clone3` answered `ENOSYS` (and, on x86_64, the x32 ABI refused).
fn second() -> Result<BpfProgram, FilterError> {
    if cfg!(target_arch = "x86_64") {
        return Ok(x86_64_abi_and_clone3());
    }
    let clone3 = SeccompFilter::new(
        [(libc::SYS_clone3, Vec::new())].into_iter().collect(),
        SeccompAction::Allow,
        SeccompAction::Errno(libc::ENOSYS as u32),
        arch()?,
    )
    .map_err(|e| FilterError(e.to_string()))?;
    BpfProgram::try_from(clone3).map_err(|e| FilterError(e.to_string()))
}

/// The bit that marks a system call number of the x32 ABI on x86_64.
pub const X32_SYSCALL_BIT: u32 = 0x4000_0000;

/// `AUDIT_ARCH_X86_64` (linux/audit.h): `EM_X86_64`, 64-bit, little-endian.
const AUDIT_ARCH_X86_64: u32 = 62 | 0x8000_0000 | 0x4000_0000;

/// The second filter on x86_64, written out (nine instructions; seccompiler has no rule for
/// a range of numbers): another architecture is killed (as the deny list does), a number
/// of the x32 ABI is refused with `EPERM`, `clone3` is answered `ENOSYS`, and the rest is
/// allowed.
fn x86_64_abi_and_clone3() -> BpfProgram {
    let stmt = |code: u32, k: u32| seccompiler::sock_filter {
        code: code as u16,
        jt: 0,
        jf: 0,
        k,
    };
    let jump = |code: u32, k: u32, jt: u8, jf: u8| seccompiler::sock_filter {
        code: code as u16,
        jt,
        jf,
        k,
    };
    // Offsets in `struct seccomp_data`: the number, then the architecture.
    let (nr, arch) = (0, 4);
    vec![
        stmt(libc::BPF_LD | libc::BPF_W | libc::BPF_ABS, arch),
        jump(
            libc::BPF_JMP | libc::BPF_JEQ | libc::BPF_K,
            AUDIT_ARCH_X86_64,
            1,
            0,
        ),
        stmt(libc::BPF_RET | libc::BPF_K, libc::SECCOMP_RET_KILL_PROCESS),
        stmt(libc::BPF_LD | libc::BPF_W | libc::BPF_ABS, nr),
        jump(
            libc::BPF_JMP | libc::BPF_JGE | libc::BPF_K,
            X32_SYSCALL_BIT,
            0,
            1,
        ),
        stmt(
            libc::BPF_RET | libc::BPF_K,
            libc::SECCOMP_RET_ERRNO | libc::EPERM as u32,
        ),
        jump(
            libc::BPF_JMP | libc::BPF_JEQ | libc::BPF_K,
            libc::SYS_clone3 as u32,
            0,
            1,
        ),
        stmt(
            libc::BPF_RET | libc::BPF_K,
            libc::SECCOMP_RET_ERRNO | libc::ENOSYS as u32,
        ),
        stmt(libc::BPF_RET | libc::BPF_K, libc::SECCOMP_RET_ALLOW),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_filters_compile_for_this_machine() {
        let filters = filters().unwrap();
        assert_eq!(filters.len(), 2);
        assert!(filters.iter().all(|f| !f.is_empty()));
        assert!(!helper_filter().unwrap().is_empty());
        assert_eq!(match_filters().unwrap().len(), 2);
    }

    #[test]
    fn the_two_parts_of_the_deny_list_are_apart() {
        assert!(
            DENIED_ALWAYS
                .iter()
                .all(|nr| !DENIED_PER_MATCH.contains(nr))
        );
        assert!(!DENIED_ALWAYS.contains(&libc::SYS_clone));
        assert!(!DENIED_PER_MATCH.contains(&libc::SYS_clone));
    }

    /// Runs a filter made of absolute loads, `jeq`/`jge` against constants and returns, as
    /// the kernel would for (`arch`, `nr`).
    fn verdict(program: &[seccompiler::sock_filter], arch: u32, nr: u32) -> u32 {
        let mut pc = 0;
        let mut a = 0u32;
        loop {
            let i = &program[pc];
            let code = u32::from(i.code);
            if code == libc::BPF_LD | libc::BPF_W | libc::BPF_ABS {
                a = match i.k {
                    0 => nr,
                    4 => arch,
                    k => panic!("a load of offset {k}"),
                };
                pc += 1;
            } else if code == libc::BPF_RET | libc::BPF_K {
                return i.k;
            } else {
                let taken = match code {
                    c if c == libc::BPF_JMP | libc::BPF_JEQ | libc::BPF_K => a == i.k,
                    c if c == libc::BPF_JMP | libc::BPF_JGE | libc::BPF_K => a >= i.k,
                    c => panic!("instruction {c:#x}"),
                };
                pc += 1 + usize::from(if taken { i.jt } else { i.jf });
            }
        }
    }

    #[test]
    fn the_second_filter_refuses_the_x32_abi_and_answers_clone3_enosys() {
        let p = x86_64_abi_and_clone3();
        let errno = |e: i32| libc::SECCOMP_RET_ERRNO | e as u32;
        let x86 = AUDIT_ARCH_X86_64;
        assert_eq!(
            verdict(&p, x86, libc::SYS_read as u32),
            libc::SECCOMP_RET_ALLOW
        );
        assert_eq!(
            verdict(&p, x86, libc::SYS_clone as u32),
            libc::SECCOMP_RET_ALLOW
        );
        assert_eq!(
            verdict(&p, x86, libc::SYS_clone3 as u32),
            errno(libc::ENOSYS)
        );
        for nr in [39, 272, 435, 0x3fff_ffff] {
            assert_eq!(
                verdict(&p, x86, X32_SYSCALL_BIT | nr),
                errno(libc::EPERM),
                "{nr}"
            );
        }
        assert_eq!(verdict(&p, x86, 0x3fff_ffff), libc::SECCOMP_RET_ALLOW);
        assert_eq!(verdict(&p, 0x4000_0003, 39), libc::SECCOMP_RET_KILL_PROCESS);
    }
}
