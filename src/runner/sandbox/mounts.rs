//! The mounts a warm match's init makes with the kernel's new mount API (`fsopen`,
//! `fsconfig`, `fsmount`, `move_mount`): the bot's folder shown through an overlay of
//! detached trees, whose lines in the mount table name no path of the host, and the
//! read-only binds of `/proc`'s parts.

use std::os::fd::{AsRawFd, FromRawFd, OwnedFd, RawFd};

/// Binds `path` onto itself read-only.
pub fn read_only_bind(path: &str) -> Result<(), nix::Error> {
    use nix::mount::{MsFlags, mount};
    let none = None::<&str>;
    mount(
        Some(path),
        path,
        none,
        MsFlags::MS_BIND | MsFlags::MS_REC,
        none,
    )?;
    mount(
        none,
        path,
        none,
        MsFlags::MS_BIND
            | MsFlags::MS_REMOUNT
            | MsFlags::MS_RDONLY
            | MsFlags::MS_NOSUID
            | MsFlags::MS_NODEV
            | MsFlags::MS_NOEXEC,
        none,
    )
}

/// `move_mount(2)` flag: the source is the descriptor itself.
const MOVE_MOUNT_F_EMPTY_PATH: libc::c_uint = 0x4;

/// Attaches the detached mount `tree` at `at`.
fn attach(tree: &OwnedFd, at: &str) -> std::io::Result<()> {
    let at = std::ffi::CString::new(at)?;
    // SAFETY: move_mount(2) with a live descriptor and NUL-terminated paths.
    let r = unsafe {
        libc::syscall(
            libc::SYS_move_mount,
            tree.as_raw_fd(),
            c"".as_ptr(),
            libc::AT_FDCWD,
            at.as_ptr(),
            MOVE_MOUNT_F_EMPTY_PATH,
        )
    };
    if r == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

/// `fsconfig(2)` commands and `fsmount(2)` attributes (linux/mount.h).
const FSCONFIG_SET_FD: libc::c_uint = 5;
const FSCONFIG_CMD_CREATE: libc::c_uint = 6;
const MOUNT_ATTR_RDONLY: libc::c_uint = 0x1;
const MOUNT_ATTR_NOSUID: libc::c_uint = 0x2;
const MOUNT_ATTR_NODEV: libc::c_uint = 0x4;

/// A descriptor a system call of the new mount API returned, or its error.
fn owned(r: libc::c_long) -> std::io::Result<OwnedFd> {
    if r < 0 {
        return Err(std::io::Error::last_os_error());
    }
    // SAFETY: the call returned a new descriptor that nothing else owns.
    Ok(unsafe { OwnedFd::from_raw_fd(r as RawFd) })
}

/// A new filesystem context of `kind` (`fsopen(2)`).
fn fs_open(kind: &std::ffi::CStr) -> std::io::Result<OwnedFd> {
    // SAFETY: fsopen(2) with a NUL-terminated name.
    owned(unsafe { libc::syscall(libc::SYS_fsopen, kind.as_ptr(), 0u32) })
}

/// `fsconfig(2)` on context `fs`: `cmd` with `key` and descriptor `aux`.
fn fs_config(
    fs: &OwnedFd,
    cmd: libc::c_uint,
    key: Option<&std::ffi::CStr>,
    aux: libc::c_int,
) -> std::io::Result<()> {
    let key = key.map_or(std::ptr::null(), std::ffi::CStr::as_ptr);
    // SAFETY: fsconfig(2) with a live context, a NUL-terminated key or null, no value.
    let r = unsafe {
        libc::syscall(
            libc::SYS_fsconfig,
            fs.as_raw_fd(),
            cmd,
            key,
            std::ptr::null::<libc::c_void>(),
            aux,
        )
    };
    if r == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

/// The detached mount of context `fs`, made with `attrs` (`fsmount(2)`).
fn fs_mount(fs: &OwnedFd, attrs: libc::c_uint) -> std::io::Result<OwnedFd> {
    fs_config(fs, FSCONFIG_CMD_CREATE, None, 0)?;
    // SAFETY: fsmount(2) with a live, created context.
    owned(unsafe { libc::syscall(libc::SYS_fsmount, fs.as_raw_fd(), 0u32, attrs) })
}

/// A detached, read-only, empty tmpfs: the lower of an overlay's two layers under the
/// bot's folder ([`attach_unnamed`]).
pub fn empty_layer() -> std::io::Result<OwnedFd> {
    fs_mount(&fs_open(c"tmpfs")?, MOUNT_ATTR_RDONLY)
}

/// Mounts the bot's folder (the detached tree `tree`) read-only at `at` as the upper of
/// the two lower layers of an overlay whose other layer is `empty` ([`empty_layer`],
/// this match's own). A bind mount's line in the mount table names the folder's path on
/// the host (the server's data folder and the bundle's hash); an overlay's layers given
/// as detached trees are shown as `/`.
pub fn attach_unnamed(tree: &OwnedFd, empty: &OwnedFd, at: &str) -> std::io::Result<()> {
    let overlay = fs_open(c"overlay")?;
    for layer in [tree, empty] {
        fs_config(
            &overlay,
            FSCONFIG_SET_FD,
            Some(c"lowerdir+"),
            layer.as_raw_fd(),
        )?;
    }
    let mounted = fs_mount(
        &overlay,
        MOUNT_ATTR_RDONLY | MOUNT_ATTR_NOSUID | MOUNT_ATTR_NODEV,
    )?;
    attach(&mounted, at)
}
