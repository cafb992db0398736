//! Archives that are refused, and why: names, links, special entries, duplicates,
//! limits, garbage.

use super::*;
// ----- names ---------------------------------------------------------

#[test]
fn absolute_paths_are_refused() {
    let err = refused(&tgz(&[T::File("/etc/x", 0o644, b"x")]), &small());
    assert!(matches!(err, BundleError::AbsolutePath { ref path } if path == "/etc/x"));
    let err = refused(&zip(&[Z::File("/etc/x", 0o644, b"x")]), &small());
    assert!(matches!(err, BundleError::AbsolutePath { .. }), "{err:?}");
}

#[test]
fn parent_components_are_refused() {
    for name in ["../x", "a/../../x", "a/../b", "ok/.."] {
        let err = refused(&tgz(&[T::File(name, 0o644, b"x")]), &small());
        assert!(matches!(err, BundleError::PathEscapes { ref path } if path == name));
        assert_eq!(
            err.to_string(),
            format!("entry {name:?} leaves the bot's directory (paths may not contain \"..\")")
        );
    }
    let err = refused(&zip(&[Z::File("../x", 0o644, b"x")]), &small());
    assert!(matches!(err, BundleError::PathEscapes { .. }), "{err:?}");
}

#[test]
fn windows_prefixes_backslashes_nul_and_empty_names_are_refused() {
    for name in ["C:/x", "c:x", "a\\b", "..\\x"] {
        let err = refused(&tgz(&[T::File(name, 0o644, b"x")]), &small());
        assert!(
            matches!(err, BundleError::InvalidName { .. }),
            "{name}: {err:?}"
        );
    }
    let err = refused(&zip(&[Z::File("..\\..\\x", 0o644, b"x")]), &small());
    assert!(matches!(err, BundleError::InvalidName { .. }), "{err:?}");
    // A tar header name stops at its first NUL; a JSON name can hold one.
    let d = dest();
    let err = write_files(&map(&[("a\0b", "x")]), &d.dest, &small()).unwrap_err();
    assert!(matches!(err, BundleError::InvalidName { .. }), "{err:?}");
    d.assert_untouched();
    // Empty names.
    let err = refused(&tgz(&[T::File("", 0o644, b"x")]), &small());
    assert!(matches!(err, BundleError::EmptyName), "{err:?}");
    let err = refused(&tgz(&[T::File("./", 0o644, b"")]), &small());
    assert!(matches!(err, BundleError::NoFiles), "{err:?}");
    let err = refused(
        &tgz(&[T::Sym(".", "x"), T::File("a", 0o644, b"")]),
        &small(),
    );
    assert!(matches!(err, BundleError::Duplicate { .. }), "{err:?}");
    let d = dest();
    let err = write_files(&map(&[("", "x")]), &d.dest, &small()).unwrap_err();
    assert!(matches!(err, BundleError::EmptyName), "{err:?}");
    // Non-UTF-8 names.
    let err = refused(
        &tgz(&[T::Raw(b"caf\xe9", EntryType::Regular, 1, b"x")]),
        &small(),
    );
    assert!(matches!(err, BundleError::InvalidName { .. }), "{err:?}");
    // Over-long names.
    let long = "a/".repeat(600) + "x";
    let d = dest();
    let err = write_files(&map(&[(&long, "x")]), &d.dest, &small()).unwrap_err();
    assert!(matches!(err, BundleError::InvalidName { .. }), "{err:?}");
}

// ----- links ---------------------------------------------------------

#[test]
fn relative_symlinks_inside_are_created() {
    let bytes = tgz(&[
        T::File("target/release/bot", 0o755, b"elf"),
        T::Sym("bin/run", "../target/release/bot"),
        T::Sym("here", "."),
        T::Sym("dangling", "not/yet/there"),
    ]);
    let (d, r) = unpack(&bytes, &small());
    let s = r.unwrap();
    assert_eq!(s.files, 1);
    let meta = fs::symlink_metadata(d.dest.join("bin/run")).unwrap();
    assert!(meta.file_type().is_symlink());
    assert_eq!(
        fs::read_link(d.dest.join("bin/run")).unwrap(),
        Path::new("../target/release/bot")
    );
    assert_eq!(d.read("bin/run"), b"elf");
    assert_eq!(d.read("here/target/release/bot"), b"elf");

    let zipped = zip(&[
        Z::File("target/release/bot", 0o755, b"elf"),
        Z::Sym("bin/run", "../target/release/bot"),
        Z::Sym("here", "."),
        Z::Sym("dangling", "not/yet/there"),
    ]);
    let (d2, r2) = unpack(&zipped, &small());
    assert_eq!(r2.unwrap().sha256, s.sha256, "links are part of the hash");
    assert_eq!(d2.read("bin/run"), b"elf");
}

#[test]
fn absolute_symlinks_are_refused() {
    let err = refused(
        &tgz(&[T::Sym("d", "/tmp"), T::File("d/x", 0o644, b"x")]),
        &small(),
    );
    assert!(
        matches!(err, BundleError::AbsoluteLink { ref path, ref target } if path == "d" && target == "/tmp"),
        "{err:?}"
    );
    let err = refused(
        &zip(&[Z::File("a", 0o644, b"x"), Z::Sym("etc", "/etc/passwd")]),
        &small(),
    );
    assert!(matches!(err, BundleError::AbsoluteLink { .. }), "{err:?}");
}

#[test]
fn symlinks_leaving_the_directory_are_refused() {
    for (name, target) in [
        ("l", ".."),
        ("l", "../x"),
        ("a/l", "../../x"),
        ("a/l", "./../b/../.."),
    ] {
        let err = refused(
            &tgz(&[T::File("f", 0o644, b"x"), T::Sym(name, target)]),
            &small(),
        );
        assert!(
            matches!(err, BundleError::LinkEscapes { .. }),
            "{target}: {err:?}"
        );
        assert!(err.to_string().contains("leaves the bot's directory"));
    }
    let err = refused(
        &zip(&[Z::File("f", 0o644, b"x"), Z::Sym("up", "../../etc")]),
        &small(),
    );
    assert!(matches!(err, BundleError::LinkEscapes { .. }), "{err:?}");
}

#[test]
fn symlinks_escaping_through_other_links_are_refused_in_any_order() {
    // `x -> .` stays inside, but `l -> x/..` then leads to dest's parent.
    let a = [
        T::Sym("x", "."),
        T::Sym("l", "x/.."),
        T::File("f", 0o644, b"x"),
    ];
    let b = [
        T::File("f", 0o644, b"x"),
        T::Sym("l", "x/.."),
        T::Sym("x", "."),
    ];
    for entries in [&a[..], &b[..]] {
        let err = refused(&tgz(entries), &small());
        assert!(
            matches!(err, BundleError::LinkEscapes { ref path, .. } if path == "l"),
            "{err:?}"
        );
    }
    // A chain deeper than Linux follows, or a loop, is refused too.
    let err = refused(
        &tgz(&[
            T::Sym("a", "b"),
            T::Sym("b", "a/x"),
            T::File("f", 0o644, b""),
        ]),
        &small(),
    );
    assert!(matches!(err, BundleError::LinkEscapes { .. }), "{err:?}");
}

#[test]
fn entries_below_a_link_or_a_file_are_refused() {
    // Parent is an (inside) link.
    let err = refused(
        &tgz(&[
            T::Dir("sub/"),
            T::Sym("d", "sub"),
            T::File("d/x", 0o644, b"x"),
        ]),
        &small(),
    );
    assert!(
        matches!(err, BundleError::NotADirectory { ref path, ref parent } if path == "d/x" && parent == "d"),
        "{err:?}"
    );
    // `link -> .` then `link/../../x`.
    let err = refused(
        &tgz(&[T::Sym("link", "."), T::File("link/../../x", 0o644, b"x")]),
        &small(),
    );
    assert!(matches!(err, BundleError::PathEscapes { .. }), "{err:?}");
    // Parent is a file.
    let err = refused(
        &tgz(&[T::File("a", 0o644, b"x"), T::File("a/b", 0o644, b"y")]),
        &small(),
    );
    assert!(matches!(err, BundleError::NotADirectory { .. }), "{err:?}");
    // Zip: a link then a file below it.
    let err = refused(
        &zip(&[Z::Sym("d", "."), Z::File("d/x", 0o644, b"x")]),
        &small(),
    );
    assert!(matches!(err, BundleError::NotADirectory { .. }), "{err:?}");
}

#[test]
fn hard_links_inside_are_copied_and_others_refused() {
    let bytes = tgz(&[
        T::File("bin/bot", 0o755, b"elf"),
        T::Hard("bot2", "bin/bot"),
        T::Hard("again", "./bin//bot"),
    ]);
    let (d, r) = unpack(&bytes, &small());
    let s = r.unwrap();
    assert_eq!((s.files, s.bytes), (3, 9));
    assert_eq!(d.read("bot2"), b"elf");
    assert_eq!(d.mode("bot2"), 0o755);
    assert!(fs::symlink_metadata(d.dest.join("bot2")).unwrap().is_file());

    type Case<'a> = (&'a [T<'a>], fn(&BundleError) -> bool);
    let cases: [Case; 4] = [
        (&[T::File("a", 0o644, b"x"), T::Hard("l", "../x")], |e| {
            matches!(e, BundleError::LinkEscapes { .. })
        }),
        (
            &[T::File("a", 0o644, b"x"), T::Hard("l", "/etc/passwd")],
            |e| matches!(e, BundleError::AbsoluteLink { .. }),
        ),
        (&[T::File("a", 0o644, b"x"), T::Hard("l", "missing")], |e| {
            matches!(e, BundleError::LinkTargetMissing { .. })
        }),
        (
            &[T::Dir("d/"), T::File("a", 0o644, b"x"), T::Hard("l", "d")],
            |e| matches!(e, BundleError::LinkTargetMissing { .. }),
        ),
    ];
    for (entries, expected) in cases {
        let err = refused(&tgz(entries), &small());
        assert!(expected(&err), "{err:?}");
    }
    // Copies count towards the size limit.
    let limits = BundleLimits {
        max_total_bytes: 5,
        max_files: 10,
    };
    let err = refused(
        &tgz(&[T::File("a", 0o644, b"abc"), T::Hard("b", "a")]),
        &limits,
    );
    assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
}

// ----- special entries -----------------------------------------------

#[test]
fn devices_fifos_and_other_special_entries_are_refused() {
    for (kind, what) in [
        (EntryType::Char, "a device file"),
        (EntryType::Block, "a device file"),
        (EntryType::Fifo, "a named pipe (fifo)"),
        (EntryType::new(b'V'), "an entry of unknown type 'V'"),
    ] {
        let err = refused(
            &tgz(&[T::File("a", 0o644, b"x"), T::Raw(b"dev", kind, 0, b"")]),
            &small(),
        );
        assert!(
            matches!(err, BundleError::SpecialFile { ref path, ref kind } if path == "dev" && kind == what),
            "{err:?}"
        );
    }
    let err = refused(
        &tgz(&[T::Raw(b"sparse", EntryType::GNUSparse, 0, b"")]),
        &small(),
    );
    assert!(
        matches!(err, BundleError::Unsupported { ref feature, .. } if feature == "a sparse file"),
        "{err:?}"
    );

    // Zip: patch the file type in the external attributes of the central directory.
    for (ftype, what) in [
        (S_IFIFO, "a named pipe (fifo)"),
        (S_IFCHR, "a device file"),
        (S_IFSOCK, "a socket"),
    ] {
        let mut bytes = zip(&[Z::File("a", 0o644, b"x"), Z::File("p", 0o644, b"")]);
        let cd = positions(&bytes, b"PK\x01\x02");
        let at = cd[1] + 38;
        bytes[at..at + 4].copy_from_slice(&((ftype | 0o644) << 16).to_le_bytes());
        let err = refused(&bytes, &small());
        assert!(
            matches!(err, BundleError::SpecialFile { ref kind, .. } if kind == what),
            "{err:?}"
        );
    }
}

#[test]
fn encrypted_zip_entries_are_refused() {
    let mut bytes = zip(&[Z::File("a", 0o644, b"secret")]);
    let local = positions(&bytes, b"PK\x03\x04")[0];
    bytes[local + 6] |= 1;
    let cd = positions(&bytes, b"PK\x01\x02")[0];
    bytes[cd + 8] |= 1;
    let err = refused(&bytes, &small());
    assert!(
        matches!(err, BundleError::Unsupported { ref feature, .. } if feature == "encryption"),
        "{err:?}"
    );
}

// ----- duplicates, empty, limits --------------------------------------

#[test]
fn duplicate_entries_are_refused() {
    let cases: [&[T]; 4] = [
        &[T::File("a", 0o644, b"1"), T::File("a", 0o644, b"2")],
        &[T::File("a", 0o644, b"1"), T::File("./a", 0o644, b"2")],
        &[T::Dir("d/"), T::Dir("d"), T::File("a", 0o644, b"1")],
        &[T::File("d/x", 0o644, b"1"), T::File("d", 0o644, b"2")],
    ];
    for entries in cases {
        let err = refused(&tgz(entries), &small());
        assert!(matches!(err, BundleError::Duplicate { .. }), "{err:?}");
    }
    // A directory entry after a file below it is fine.
    let (_d, r) = unpack(&tgz(&[T::File("d/x", 0o644, b"1"), T::Dir("d/")]), &small());
    r.unwrap();

    // Zip: the writer refuses duplicates, so rename "b.txt" to "a.txt".
    let mut bytes = zip(&[Z::File("a.txt", 0o644, b"1"), Z::File("b.txt", 0o644, b"2")]);
    replace_all(&mut bytes, b"b.txt", b"a.txt");
    let err = refused(&bytes, &small());
    assert!(
        matches!(err, BundleError::Duplicate { ref path } if path == "a.txt"),
        "{err:?}"
    );
    let err = refused(
        &zip(&[Z::File("a", 0o644, b"1"), Z::File("./a", 0o644, b"2")]),
        &small(),
    );
    assert!(matches!(err, BundleError::Duplicate { .. }), "{err:?}");

    // JSON: names that normalise to the same path.
    let d = dest();
    let err = write_files(&map(&[("a/b", "1"), ("a//b", "2")]), &d.dest, &small()).unwrap_err();
    assert!(matches!(err, BundleError::Duplicate { .. }), "{err:?}");
    d.assert_untouched();
}

#[test]
fn empty_bundles_are_refused() {
    for bytes in [
        tgz(&[]),
        tar(&[]),
        tgz(&[T::Dir("./"), T::Dir("src/")]),
        zip(&[]),
        zip(&[Z::Dir("src/")]),
    ] {
        let err = refused(&bytes, &small());
        assert!(matches!(err, BundleError::NoFiles), "{err:?}");
        assert_eq!(err.to_string(), "the bot has no files");
    }
    assert!(zip(&[]).starts_with(b"PK\x05\x06"));
    let d = dest();
    let err = write_files(&BTreeMap::new(), &d.dest, &small()).unwrap_err();
    assert!(matches!(err, BundleError::NoFiles), "{err:?}");
    d.assert_untouched();
}

#[test]
fn too_many_files_are_refused() {
    let limits = BundleLimits {
        max_total_bytes: 1024,
        max_files: 3,
    };
    let (_d, r) = unpack(
        &tgz(&[
            T::File("a", 0o644, b""),
            T::File("b", 0o644, b""),
            T::File("c", 0o644, b""),
        ]),
        &limits,
    );
    r.unwrap();
    let names: Vec<String> = (0..4).map(|i| format!("f{i}")).collect();
    let entries: Vec<T> = names.iter().map(|n| T::File(n, 0o644, b"")).collect();
    let err = refused(&tgz(&entries), &limits);
    assert!(
        matches!(err, BundleError::TooManyFiles { limit: 3, ref path } if path == "f3"),
        "{err:?}"
    );
    // Implicit parent directories count.
    let err = refused(&tgz(&[T::File("a/b/c/d", 0o644, b"")]), &limits);
    assert!(matches!(err, BundleError::TooManyFiles { .. }), "{err:?}");
    let zipped = zip(&[
        Z::File("a", 0o644, b""),
        Z::File("b", 0o644, b""),
        Z::Dir("c/"),
        Z::File("d", 0o644, b""),
    ]);
    let err = refused(&zipped, &limits);
    assert!(matches!(err, BundleError::TooManyFiles { .. }), "{err:?}");
    let d = dest();
    let many = map(&[("a", ""), ("b", ""), ("c", ""), ("d", "")]);
    let err = write_files(&many, &d.dest, &limits).unwrap_err();
    assert!(matches!(err, BundleError::TooManyFiles { .. }), "{err:?}");
    d.assert_untouched();
}

#[test]
fn declared_size_over_the_limit_is_refused_before_reading() {
    // The header claims 1 GiB; no data follows (so reading it would say "truncated").
    let bytes = tgz(&[T::Raw(b"big", EntryType::Regular, 1 << 30, b"")]);
    let err = refused(&bytes, &BundleLimits::default());
    assert!(
        matches!(err, BundleError::TooLarge { ref path, .. } if path.as_deref() == Some("big")),
        "{err:?}"
    );
    // Within the limit on its own, but not together with what came before.
    let limits = BundleLimits {
        max_total_bytes: 10,
        max_files: 10,
    };
    let err = refused(
        &tgz(&[
            T::File("a", 0o644, b"123456"),
            T::File("b", 0o644, b"12345"),
        ]),
        &limits,
    );
    assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
    let err = refused(
        &zip(&[
            Z::File("a", 0o644, b"123456"),
            Z::File("b", 0o644, b"12345"),
        ]),
        &limits,
    );
    assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
    let d = dest();
    let err = write_files(&map(&[("a", "123456"), ("b", "12345")]), &d.dest, &limits).unwrap_err();
    assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
    d.assert_untouched();
}

#[test]
fn gzip_bomb_is_refused_without_being_unpacked() {
    // 16 MiB of zeros compress to ~16 KiB; the limit is 1 MiB.
    let zeros = vec![0u8; 16 << 20];
    let bytes = tgz(&[T::File("zeros", 0o644, &zeros)]);
    assert!(bytes.len() < 100_000);
    let err = refused(&bytes, &small());
    assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
    // The same zeros hidden as "data" of a directory entry, which is
    // skipped rather than written: the decompressed stream is capped.
    let bytes = tgz(&[
        T::Raw(b"dir/", EntryType::Directory, zeros.len() as u64, &zeros),
        T::File("a", 0o644, b"x"),
    ]);
    let err = refused(&bytes, &small());
    assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
    // And as trailing padding after the end of the archive.
    let mut inner = tar(&[T::File("a", 0o644, b"x")]);
    inner.extend_from_slice(&zeros);
    let err = refused(&gz(&inner), &small());
    assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
}

#[test]
fn zip_entry_larger_than_declared_is_refused() {
    // 2 MiB of zeros, but both headers claim 1000 bytes; the limit is 1 MiB.
    let zeros = vec![0u8; 2 << 20];
    let mut bytes = zip(&[Z::File("bomb", 0o644, &zeros)]);
    let local = positions(&bytes, b"PK\x03\x04")[0];
    bytes[local + 22..local + 26].copy_from_slice(&1000u32.to_le_bytes());
    let cd = positions(&bytes, b"PK\x01\x02")[0];
    bytes[cd + 24..cd + 28].copy_from_slice(&1000u32.to_le_bytes());
    let err = refused(&bytes, &small());
    assert!(
        matches!(
            err,
            BundleError::TooLarge { .. } | BundleError::Corrupt { .. }
        ),
        "{err:?}"
    );
    // With a roomy limit, the lie itself is caught.
    let err = refused(&bytes, &BundleLimits::default());
    assert!(matches!(err, BundleError::Corrupt { .. }), "{err:?}");
}

// ----- garbage, truncation --------------------------------------------

#[test]
fn garbage_is_refused_naming_the_accepted_formats() {
    for bytes in [
        &b""[..],
        b"hello world",
        b"\x7fELF\x02\x01\x01",
        &[0u8; 600],
    ] {
        let err = refused(bytes, &small());
        assert!(matches!(err, BundleError::UnrecognisedFormat), "{err:?}");
        let msg = err.to_string();
        for fmt in [".tar.gz", ".tar", ".zip"] {
            assert!(msg.contains(fmt), "{msg}");
        }
    }
    // Right magic, wrong insides.
    let err = refused(b"\x1f\x8bthis is not deflate data at all", &small());
    assert!(
        matches!(
            err,
            BundleError::Corrupt { .. } | BundleError::Truncated { .. }
        ),
        "{err:?}"
    );
    let err = refused(
        &gz(b"not a tar archive, just text that is long enough"),
        &small(),
    );
    assert!(
        matches!(
            err,
            BundleError::Truncated { .. } | BundleError::Corrupt { .. }
        ),
        "{err:?}"
    );
    let err = refused(&gz(&[7u8; 4096]), &small());
    assert!(matches!(err, BundleError::Corrupt { .. }), "{err:?}");
    let err = refused(b"PK\x03\x04garbage", &small());
    assert!(matches!(err, BundleError::Corrupt { .. }), "{err:?}");
}

#[test]
fn truncated_archives_are_refused() {
    let data: Vec<u8> = (0..200_000u32).map(|i| (i * 7919 % 251) as u8).collect();
    let full = tgz(&[T::File("a", 0o644, b"x"), T::File("big", 0o644, &data)]);
    for cut in [full.len() / 2, full.len() - 4, 20] {
        let err = refused(&full[..cut], &BundleLimits::default());
        assert!(
            matches!(
                err,
                BundleError::Truncated {
                    format: ".tar.gz",
                    ..
                }
            ),
            "{cut}: {err:?}"
        );
        assert!(
            err.to_string()
                .starts_with("the .tar.gz archive is truncated")
        );
    }
    let plain = tar(&[T::File("a", 0o644, b"x"), T::File("big", 0o644, &data)]);
    let err = refused(&plain[..plain.len() / 2], &BundleLimits::default());
    assert!(
        matches!(err, BundleError::Truncated { format: ".tar", ref entry } if entry.as_deref() == Some("big")),
        "{err:?}"
    );
    let zipped = zip(&[Z::File("a", 0o644, &data)]);
    let err = refused(&zipped[..zipped.len() - 10], &BundleLimits::default());
    assert!(
        matches!(
            err,
            BundleError::Corrupt { .. } | BundleError::Truncated { .. }
        ),
        "{err:?}"
    );
}
