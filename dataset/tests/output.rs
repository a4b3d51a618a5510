//! Output files are created safely: no write through a symbolic link, no
//! overwrite without `overwrite`, never over an input, errors reported.

use dataset::output::{check_replaceable, create_dir, create_file, write_file};
use std::io::ErrorKind;

/// A fresh folder for one test, removed when the test passes.
fn tmpdir(name: &str) -> scratch::ScratchDir {
    scratch::ScratchDir::new(&format!("output-{name}"))
}

#[test]
fn a_symlink_as_output_file_is_refused_even_with_overwrite() {
    let d = tmpdir("symlink");
    let victim = d.join("victim.txt");
    std::fs::write(&victim, "keep me").unwrap();
    let link = d.join("out.csv");
    std::os::unix::fs::symlink(&victim, &link).unwrap();
    for overwrite in [false, true] {
        let e = write_file(&link, b"garbage", overwrite, &[]).unwrap_err();
        assert!(e.to_string().contains("is a symbolic link"), "{e}");
    }
    // a dangling link is refused too (it would create the target)
    let dangling = d.join("dangling.csv");
    std::os::unix::fs::symlink(d.join("nowhere.txt"), &dangling).unwrap();
    let e = write_file(&dangling, b"x", true, &[]).unwrap_err();
    assert!(e.to_string().contains("is a symbolic link"), "{e}");
    assert!(!d.join("nowhere.txt").exists());
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep me");
}

#[test]
fn a_symlinked_output_directory_is_refused() {
    let d = tmpdir("symdir");
    let real = d.join("real");
    std::fs::create_dir(&real).unwrap();
    let link = d.join("out");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    let e = create_dir(&link).unwrap_err();
    assert!(e.to_string().contains("is a symbolic link"), "{e}");
    // a file where a directory is asked for
    std::fs::write(d.join("file"), "x").unwrap();
    let e = create_dir(&d.join("file")).unwrap_err();
    assert!(e.to_string().contains("not a directory"), "{e}");
    // a fresh nested directory, and an existing one, are fine
    create_dir(&d.join("a/b/c")).unwrap();
    create_dir(&d.join("a/b/c")).unwrap();
    assert!(d.join("a/b/c").is_dir());
}

#[test]
fn an_existing_file_is_kept_without_overwrite_and_replaced_with_it() {
    let d = tmpdir("exists");
    let p = d.join("out.json");
    write_file(&p, b"first, longer content", false, &[]).unwrap();
    let e = write_file(&p, b"second", false, &[]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::AlreadyExists);
    assert!(e.to_string().contains("use --force"), "{e}");
    assert_eq!(std::fs::read_to_string(&p).unwrap(), "first, longer content");
    write_file(&p, b"second", true, &[]).unwrap();
    assert_eq!(std::fs::read_to_string(&p).unwrap(), "second");
}

/// A file in a folder that is not there is refused by the check a command
/// makes before its work, naming the folder; nothing is created.
#[test]
fn an_output_in_a_missing_folder_is_refused_before_the_work() {
    let d = tmpdir("missing");
    let out = d.join("cal").join("rig.toml");
    for overwrite in [false, true] {
        let e = check_replaceable(&out, overwrite, &[]).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::NotFound);
        let folder = d.join("cal");
        assert!(
            e.to_string()
                .contains(&format!("its folder {} does not exist", folder.display())),
            "{e}"
        );
    }
    assert!(!d.join("cal").exists());
    // a file where the folder should be
    std::fs::write(d.join("cal"), "x").unwrap();
    let e = check_replaceable(&out, false, &[]).unwrap_err();
    assert!(e.to_string().contains("is not a directory"), "{e}");
    // a bare file name is in the working directory, which is there
    check_replaceable(std::path::Path::new("surely-absent-output.toml"), false, &[]).unwrap();
}

#[test]
fn an_input_is_never_overwritten() {
    let d = tmpdir("input");
    let input = d.join("estimates.csv");
    std::fs::write(&input, "t,u\n0,0\n").unwrap();
    // the same path, another spelling of it, and a hard link to it
    let other = d.join(".").join("estimates.csv");
    let hard = d.join("hard.csv");
    std::fs::hard_link(&input, &hard).unwrap();
    for out in [&input, &other, &hard] {
        for overwrite in [false, true] {
            let e = create_file(out, overwrite, &[input.as_path()]).unwrap_err();
            assert!(e.to_string().contains("is the input"), "{}: {e}", out.display());
        }
    }
    assert_eq!(std::fs::read_to_string(&input).unwrap(), "t,u\n0,0\n");
}

#[test]
fn a_full_disk_is_an_error_not_a_panic() {
    // /dev/full: opening works (with overwrite: it exists), every write fails with ENOSPC
    let full = std::path::Path::new("/dev/full");
    if !full.exists() {
        eprintln!("no /dev/full here: skipped");
        return;
    }
    let e = write_file(full, &[b'x'; 100_000], true, &[]).unwrap_err();
    assert_eq!(e.raw_os_error(), Some(28), "{e}"); // ENOSPC
    let samples = vec![dataset::Sample::new(0.0, 0.0, 0.3, 6.9e6, 6.9e6); 10_000];
    let e = dataset::write_csv(full, &samples, true).unwrap_err();
    assert!(
        e.to_string().starts_with("/dev/full: No space left on device"),
        "{e}"
    );
    // without overwrite an existing device is not touched
    let e = write_file(full, b"x", false, &[]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::AlreadyExists);
}
