//! Tests of the prefixes' files: which prefixes have files, and which files a prefix owns.

use super::*;

#[test]
fn the_prefixes_with_files_are_read_off_their_names() {
    let base = std::env::temp_dir().join(format!("lw-prefixes-{}", std::process::id()));
    let (shm, iox) = (base.join("shm"), base.join("iox"));
    std::fs::create_dir_all(&shm).unwrap();
    std::fs::create_dir_all(iox.join("lab_1/services")).unwrap();
    std::fs::create_dir_all(iox.join("bad name")).unwrap();
    // a directory with other things in it is no iceoryx2 root
    std::fs::create_dir_all(iox.join("Documents/notes")).unwrap();
    std::fs::write(iox.join("lab_1.lock"), "").unwrap();
    let hash = "0354a209029e7d094a819e2d4030ea331e6caaf0";
    for name in [
        format!("lw_lab_{hash}_1029966520912543268563897568756.data"),
        format!("lw_lab_1_{hash}_node.0_10_0.global_mgmt"),
        format!("lw_run4242_{hash}_102996.data"),
        "lw_short_0354a209.data".to_string(),
        format!("iox2_{hash}_x.data"),
    ] {
        std::fs::write(shm.join(name), b"").unwrap();
    }
    let found = prefixes_with_files_in(&shm, &iox);
    std::fs::remove_dir_all(&base).unwrap();
    assert_eq!(found, ["lab", "lab_1", "run4242"]);
}

#[test]
fn a_prefix_owns_its_files_and_not_those_of_a_longer_prefix() {
    let hash = "0354a209029e7d094a819e2d4030ea331e6caaf0";
    assert!(is_prefix_file(
        &format!("lw_lab_{hash}_1029966520912543268563897568756.data"),
        "lw_lab_"
    ));
    assert!(is_prefix_file(
        &format!("lw_lab_{hash}_node.0_10_0.global_mgmt"),
        "lw_lab_"
    ));
    // prefix `lab_1`'s files begin with `lw_lab_` too
    assert!(!is_prefix_file(
        &format!("lw_lab_1_{hash}_102996.data"),
        "lw_lab_"
    ));
    assert!(is_prefix_file(
        &format!("lw_lab_1_{hash}_102996.data"),
        "lw_lab_1_"
    ));
    assert!(!is_prefix_file("lw_lab_0354a209.data", "lw_lab_"));
    assert!(!is_prefix_file(&format!("iox2_{hash}.data"), "lw_lab_"));
}
