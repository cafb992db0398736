//! Archives that unpack: round trips, the content hash, the destination.

use super::*;
// ----- round trips ---------------------------------------------------

#[test]
fn tar_gz_round_trips_nested_dirs_and_exec_bit() {
    let bytes = tgz(&[
        T::Dir("./"),
        T::Dir("./src/"),
        T::File("./src/main.py", 0o644, b"print('hi')\n"),
        T::Dir("./bin/"),
        T::File("./bin/bot", 0o700, b"\x7fELF..."),
        T::File("./src/deep/er/data.txt", 0o664, b"nested"),
    ]);
    let (d, r) = unpack(&bytes, &BundleLimits::default());
    let s = r.unwrap();
    assert_eq!(s.files, 3);
    assert_eq!(s.bytes, 12 + 7 + 6);
    assert_eq!(s.sha256.len(), 64);
    assert_eq!(d.read("src/main.py"), b"print('hi')\n");
    assert_eq!(d.read("bin/bot"), b"\x7fELF...");
    assert_eq!(d.read("src/deep/er/data.txt"), b"nested");
    assert_eq!(d.mode("bin/bot"), 0o755);
    assert_eq!(d.mode("src/main.py"), 0o644);
    assert_eq!(d.mode("src/deep/er/data.txt"), 0o644);
    assert_eq!(d.mode("src/deep"), 0o755);
    // No staging directory left next to dest.
    assert_eq!(fs::read_dir(d.parent.path()).unwrap().count(), 1);
}

#[test]
fn zip_round_trips_nested_dirs_and_exec_bit() {
    let bytes = zip(&[
        Z::Dir("src/"),
        Z::File("src/main.py", 0o644, b"print('hi')\n"),
        Z::File("bin/bot", 0o755, b"\x7fELF..."),
        Z::File("src/deep/er/data.txt", 0o600, b"nested"),
    ]);
    let (d, r) = unpack(&bytes, &BundleLimits::default());
    let s = r.unwrap();
    assert_eq!((s.files, s.bytes), (3, 25));
    assert_eq!(d.read("src/main.py"), b"print('hi')\n");
    assert_eq!(d.read("bin/bot"), b"\x7fELF...");
    assert_eq!(d.read("src/deep/er/data.txt"), b"nested");
    assert_eq!(d.mode("bin/bot"), 0o755);
    assert_eq!(d.mode("src/main.py"), 0o644);
    assert_eq!(d.mode("src/deep/er/data.txt"), 0o644);
}

#[test]
fn plain_tar_is_accepted() {
    let bytes = tar(&[T::File("bot.py", 0o755, b"x")]);
    let (d, r) = unpack(&bytes, &BundleLimits::default());
    assert_eq!(r.unwrap().files, 1);
    assert_eq!(d.mode("bot.py"), 0o755);
}

#[test]
fn pax_global_header_is_skipped() {
    // `git archive` starts with a pax global header holding the commit id.
    let pax = b"52 comment=0123456789012345678901234567890123456789\n";
    let bytes = tgz(&[
        T::Raw(
            b"pax_global_header",
            EntryType::XGlobalHeader,
            pax.len() as u64,
            pax,
        ),
        T::File("bot/run.sh", 0o755, b"#!/bin/sh\n"),
    ]);
    let (d, r) = unpack(&bytes, &BundleLimits::default());
    assert_eq!(r.unwrap().files, 1);
    assert_eq!(d.read("bot/run.sh"), b"#!/bin/sh\n");
}

#[test]
fn destination_keeps_its_permissions() {
    let d = dest();
    fs::set_permissions(&d.dest, fs::Permissions::from_mode(0o750)).unwrap();
    unpack_archive(&tgz(&[T::File("a", 0o644, b"a")]), &d.dest, &small()).unwrap();
    assert_eq!(d.mode(""), 0o750);
}

// ----- hash ----------------------------------------------------------

#[test]
fn hash_is_independent_of_format_order_and_timestamps() {
    let files = [
        ("src/main.py", "print('hi')\n"),
        ("README", "bot"),
        ("src/a", ""),
    ];
    let written = |files: &[(&str, &str)]| {
        let d = dest();
        write_files(&map(files), &d.dest, &small()).unwrap().sha256
    };
    let unpacked = |bytes: &[u8]| unpack(bytes, &small()).1.unwrap().sha256;
    let json = written(&files);
    let tar_gz = unpacked(&tgz(&[
        T::Dir("src/"),
        T::File("./src/main.py", 0o644, b"print('hi')\n"),
        T::File("README", 0o600, b"bot"),
        T::File("src/a", 0o644, b""),
    ]));
    let zip_reordered = unpacked(&zip(&[
        Z::File("src/a", 0o644, b""),
        Z::File("README", 0o644, b"bot"),
        Z::File("src/main.py", 0o644, b"print('hi')\n"),
    ]));
    assert_eq!(json, tar_gz);
    assert_eq!(json, zip_reordered);

    // One byte changed.
    let changed = written(&[
        ("src/main.py", "print('hI')\n"),
        ("README", "bot"),
        ("src/a", ""),
    ]);
    assert_ne!(json, changed);

    // The executable bit counts.
    let exec = unpacked(&tgz(&[
        T::File("src/main.py", 0o755, b"print('hi')\n"),
        T::File("README", 0o644, b"bot"),
        T::File("src/a", 0o644, b""),
    ]));
    assert_ne!(json, exec);

    // A renamed file counts.
    let renamed = written(&[
        ("src/main.py", "print('hi')\n"),
        ("README", "bot"),
        ("src/b", ""),
    ]);
    assert_ne!(json, renamed);
}

#[test]
fn hash_follows_the_documented_scheme() {
    let d = dest();
    let s = write_files(&map(&[("a", "x")]), &d.dest, &small()).unwrap();
    let mut h = Sha256::new();
    h.update(b"mazearena-bundle-v1\n");
    h.update(b"F");
    h.update(1u64.to_be_bytes());
    h.update(b"a");
    h.update(1u64.to_be_bytes());
    h.update(Sha256::digest(b"x"));
    assert_eq!(s.sha256, hex(&h.finalize()));
}

// ----- write_files, destination, error mapping -------------------------

#[test]
fn write_files_creates_nested_files() {
    let d = dest();
    let files = map(&[
        ("bot.py", "import sys\n"),
        ("lib/util.py", "X = 1\n"),
        ("./lib/x/y.txt", ""),
    ]);
    let s = write_files(&files, &d.dest, &BundleLimits::default()).unwrap();
    assert_eq!((s.files, s.bytes), (3, 17));
    assert_eq!(d.read("lib/util.py"), b"X = 1\n");
    assert_eq!(d.read("lib/x/y.txt"), b"");
    assert_eq!(d.mode("bot.py"), 0o644);
    assert_eq!(d.mode("lib/x"), 0o755);

    for bad in ["../x", "/abs", "dir/", "a\\b"] {
        let d = dest();
        let err = write_files(&map(&[("ok", "1"), (bad, "2")]), &d.dest, &small()).unwrap_err();
        assert!(err.is_client_error(), "{err:?}");
        d.assert_untouched();
    }
}

#[test]
fn destination_must_be_an_existing_empty_directory() {
    let bytes = tgz(&[T::File("a", 0o644, b"x")]);
    let d = dest();
    fs::write(d.dest.join("old"), b"old").unwrap();
    let err = unpack_archive(&bytes, &d.dest, &small()).unwrap_err();
    assert!(matches!(err, BundleError::Destination { .. }), "{err:?}");
    assert!(!err.is_client_error());
    assert_eq!(d.read("old"), b"old");

    let missing = d.parent.path().join("missing");
    let err = unpack_archive(&bytes, &missing, &small()).unwrap_err();
    assert!(matches!(err, BundleError::Destination { .. }), "{err:?}");
    assert!(!missing.exists());

    let link = d.parent.path().join("link");
    let empty = d.parent.path().join("empty");
    fs::create_dir(&empty).unwrap();
    std::os::unix::fs::symlink(&empty, &link).unwrap();
    let err = unpack_archive(&bytes, &link, &small()).unwrap_err();
    assert!(matches!(err, BundleError::Destination { .. }), "{err:?}");
    assert_eq!(fs::read_dir(&empty).unwrap().count(), 0);
}

#[test]
fn only_io_and_destination_errors_are_server_errors() {
    let io = BundleError::Io {
        action: "write file".into(),
        source: io::Error::other("disk full"),
    };
    assert!(!io.is_client_error());
    assert_eq!(io.to_string(), "could not write file: disk full");
    assert!(BundleError::NoFiles.is_client_error());
    assert!(BundleError::UnrecognisedFormat.is_client_error());
    assert!(
        BundleError::TooLarge {
            limit: 1,
            path: None
        }
        .is_client_error()
    );
}
