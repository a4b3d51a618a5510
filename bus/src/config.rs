//! The bus configuration ([`BusConfig`]): service sizes and the isolation
//! prefix, with what a prefix owns (its lock, its files, why a start is blocked).

use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;

use crate::BusError;

/// The environment variable that isolates a set of processes (see [`BusConfig::from_env`]).
pub const PREFIX_ENV: &str = "LEAKWATCH_IOX_PREFIX";

/// The longest isolation prefix, characters. Measured with iceoryx2 0.10
/// (bus/tests/prefix.rs): an event listener's Unix socket is
/// `<root>/lw_<prefix>_<id>.event`, the prefix twice (the root is
/// `<private dir>/<prefix>/`), and
/// its path must fit the 108 bytes of a socket address (a 24-character prefix
/// worked with a 32-digit id, 108 bytes, and failed with `ResourceCreationFailed`
/// at 33 digits, 109 bytes). The id is a 128-bit number whose top 32 bits
/// count the ids the process made: 30 digits at first, up to 39. So 28 + 2 ×
/// prefix + 39 ≤ 108 bytes: 20 characters work whatever the count; 25 fail at once.
/// A private directory longer than `/tmp/leakwatch-0` allows fewer
/// ([`max_prefix_len_under`]).
pub const MAX_PREFIX_LEN: usize = 20;

/// The longest path of a Unix socket, bytes (`sun_path` of `sockaddr_un`).
const SOCKET_PATH_MAX: usize = 108;

/// Bytes of an event socket's path beyond the root and the prefix:
/// `lw_`, `_`, an id of up to 39 digits and `.event`.
const SOCKET_NAME_EXTRA: usize = 3 + 1 + 39 + 6;

/// The longest prefix whose event sockets fit [`SOCKET_PATH_MAX`] when the
/// private directory is `dir` (root `<dir>/<prefix>/`), at most [`MAX_PREFIX_LEN`].
pub fn max_prefix_len_under(dir: &std::path::Path) -> usize {
    let fixed = dir.as_os_str().len() + 2 + SOCKET_NAME_EXTRA;
    (SOCKET_PATH_MAX.saturating_sub(fixed) / 2).min(MAX_PREFIX_LEN)
}

/// Sizes of the services and the isolation prefix. Every process of a rig
/// must use the same values: the first process creates the services and the
/// others open them only if their requirements fit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BusConfig {
    /// Isolation prefix (1 to [`MAX_PREFIX_LEN`] characters of `[A-Za-z0-9_-]`): iceoryx2 files get the
    /// prefix `lw_<prefix>_`; its segments are in `/dev/shm`, its other files under
    /// `<private dir>/<prefix>/` ([`crate::private_dir`]).
    /// `None`: iceoryx2's defaults (what other iceoryx2 programs, like the
    /// Python bindings with a default config, see).
    pub iox_prefix: Option<String>,
    /// Frames a subscriber buffers before the oldest is overwritten (a 1 kHz
    /// stream survives a stall of this many ms).
    pub subscriber_buffer: usize,
    /// Frames a late subscriber receives on connecting.
    pub history: usize,
    /// Publishers per service (a restarted publisher needs a free slot while
    /// its dead predecessor is being cleaned up).
    pub max_publishers: usize,
    /// Subscribers per service (the next stage, the recorder, a Python
    /// viewer, restarts).
    pub max_subscribers: usize,
    /// Nodes (processes) per service.
    pub max_nodes: usize,
}

impl Default for BusConfig {
    fn default() -> Self {
        BusConfig {
            iox_prefix: None,
            subscriber_buffer: 256,
            history: 0,
            max_publishers: 8,
            max_subscribers: 16,
            max_nodes: 32,
        }
    }
}

impl BusConfig {
    /// The defaults, with [`BusConfig::iox_prefix`] from `LEAKWATCH_IOX_PREFIX`
    /// if it is set and not empty.
    pub fn from_env() -> Result<BusConfig, BusError> {
        let mut c = BusConfig::default();
        match std::env::var(PREFIX_ENV) {
            Ok(p) if !p.is_empty() => {
                validate_prefix(&p)?;
                c.iox_prefix = Some(p);
            }
            Ok(_) | Err(std::env::VarError::NotPresent) => {}
            Err(e) => return Err(BusError(format!("{PREFIX_ENV}: {e}"))),
        }
        Ok(c)
    }

    /// The iceoryx2 configuration for these settings.
    pub fn iceoryx2_config(&self) -> Result<iceoryx2::config::Config, BusError> {
        let mut c = iceoryx2::config::Config::global_config().clone();
        if let Some(p) = &self.iox_prefix {
            validate_prefix(p)?;
            c.global.prefix = FileName::new(format!("lw_{p}_").as_bytes())
                .map_err(|e| BusError::new(format!("iceoryx2 prefix from {p:?}"), e))?;
            let dir = crate::private_dir()?;
            let max = max_prefix_len_under(&dir);
            if p.len() > max {
                return Err(BusError(format!(
                    "iceoryx2 isolation prefix {p:?} (from {PREFIX_ENV}?) has {} characters; at most {max} work \
                     with the private directory {}: iceoryx2 puts the prefix twice into the path of a Unix \
                     socket (<dir>/<prefix>/lw_<prefix>_<id of up to 39 digits>.event), which must fit \
                     {SOCKET_PATH_MAX} bytes; use a shorter prefix or a shorter {}",
                    p.len(),
                    dir.display(),
                    crate::private::RUNTIME_DIR_ENV
                )));
            }
            let root = format!("{}/", dir.join(p).display());
            c.global
                .set_root_path(&Path::new(root.as_bytes()).map_err(|e| BusError::new(&root, e))?);
        }
        Ok(c)
    }
}

impl BusConfig {
    /// Removes the files an isolated run leaves behind (`<private dir>/<prefix>/`
    /// and `/dev/shm/lw_<prefix>_*`); for tests, once every process of the
    /// prefix has ended. Does nothing without a prefix. Returns the entries removed.
    pub fn remove_isolated_files(&self) -> std::io::Result<usize> {
        let Some(p) = &self.iox_prefix else {
            return Ok(0);
        };
        validate_prefix(p).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e.0))?;
        let mut removed = 0;
        let root = crate::private_dir_path().join(p);
        if is_iox_root(&root, p) {
            std::fs::remove_dir_all(&root)?;
            removed += 1;
        }
        let start = format!("lw_{p}_");
        for entry in std::fs::read_dir("/dev/shm")?.flatten() {
            if entry.file_name().to_string_lossy().starts_with(&start) {
                std::fs::remove_file(entry.path())?;
                removed += 1;
            }
        }
        Ok(removed)
    }
}

/// One file or directory a prefix's processes left behind.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Leftover {
    /// The file (`/dev/shm/lw_<prefix>_*`) or directory (`<private dir>/<prefix>`).
    pub path: std::path::PathBuf,
    /// Its size, bytes (a directory: the sum of the files in it).
    pub bytes: u64,
}

/// Whether `name` (a file name in `/dev/shm`) belongs to the prefix whose
/// iceoryx2 file prefix is `start` (`lw_<prefix>_`): iceoryx2 names follow the
/// file prefix with a 40-digit hexadecimal hash, so the files of a longer prefix
/// that begins the same way (`lab` and `lab_1`) are not taken for this one's.
fn is_prefix_file(name: &str, start: &str) -> bool {
    let Some(rest) = name.strip_prefix(start) else {
        return false;
    };
    let hex = rest.bytes().take_while(u8::is_ascii_hexdigit).count();
    hex >= 40 && matches!(rest.as_bytes().get(hex), Some(b'_' | b'.'))
}

/// The prefixes that have iceoryx2 files of leakwatch's naming in `shm_dir`
/// (`lw_<prefix>_<40 hex digits>...`) or `iox_dir` (the private directory:
/// `<prefix>/`), sorted, each once; names that are not a valid prefix are left out.
pub fn prefixes_with_files_in(shm_dir: &std::path::Path, iox_dir: &std::path::Path) -> Vec<String> {
    let mut out = Vec::new();
    if let Ok(dir) = std::fs::read_dir(iox_dir) {
        for e in dir.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if is_iox_root(&e.path(), &name) {
                out.push(name);
            }
        }
    }
    if let Ok(dir) = std::fs::read_dir(shm_dir) {
        for e in dir.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let Some(rest) = name.strip_prefix("lw_") else {
                continue;
            };
            // the prefix ends at the first '_' the hash follows
            let found = rest
                .match_indices('_')
                .map(|(i, _)| &rest[..i])
                .find(|p| is_prefix_file(&name, &format!("lw_{p}_")));
            if let Some(p) = found {
                out.push(p.to_string());
            }
        }
    }
    out.retain(|p| validate_prefix(p).is_ok());
    out.sort();
    out.dedup();
    out
}

/// Whether `dir` is the iceoryx2 root of prefix `p`, so that it may be removed
/// as such: a real directory (not a link) that holds nothing but what iceoryx2
/// puts there (`services`, `nodes`, files named `lw_<p>_...`); anything else
/// (a directory of the user's that happens to be in a private directory set
/// by `LEAKWATCH_RUNTIME_DIR`) is never taken for one.
fn is_iox_root(dir: &std::path::Path, p: &str) -> bool {
    let start = format!("lw_{p}_");
    let is_dir = std::fs::symlink_metadata(dir).is_ok_and(|m| m.is_dir());
    is_dir
        && std::fs::read_dir(dir).is_ok_and(|entries| {
            entries.flatten().all(|e| {
                let n = e.file_name().to_string_lossy().into_owned();
                n == "services" || n == "nodes" || n.starts_with(&start)
            })
        })
}

/// [`prefixes_with_files_in`] `/dev/shm` and the private directory.
pub fn prefixes_with_files() -> Vec<String> {
    prefixes_with_files_in(std::path::Path::new("/dev/shm"), &crate::private_dir_path())
}

/// Bytes of the files under `path` (0 for what cannot be read).
fn size_of(path: &std::path::Path) -> u64 {
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return 0;
    };
    if !meta.is_dir() {
        return meta.len();
    }
    std::fs::read_dir(path)
        .map(|d| d.flatten().map(|e| size_of(&e.path())).sum())
        .unwrap_or(0)
}

impl BusConfig {
    /// The files of this config's prefix as they are now: the directory
    /// `<private dir>/<prefix>` and the segments `/dev/shm/lw_<prefix>_*`.
    /// Empty without a prefix (iceoryx2's default prefix is shared with other programs).
    pub fn prefix_files(&self) -> Vec<Leftover> {
        let Some(p) = &self.iox_prefix else {
            return Vec::new();
        };
        if validate_prefix(p).is_err() {
            return Vec::new();
        }
        let (start, root) = self.file_prefix_and_root();
        let mut out = Vec::new();
        let root = std::path::PathBuf::from(root);
        if std::fs::symlink_metadata(&root).is_ok() && is_iox_root(&root, p) {
            out.push(Leftover {
                bytes: size_of(&root),
                path: root,
            });
        }
        if let Ok(dir) = std::fs::read_dir("/dev/shm") {
            let mut shm: Vec<Leftover> = dir
                .flatten()
                .filter(|e| is_prefix_file(&e.file_name().to_string_lossy(), &start))
                .map(|e| Leftover {
                    bytes: size_of(&e.path()),
                    path: e.path(),
                })
                .collect();
            shm.sort_by(|a, b| a.path.cmp(&b.path));
            out.extend(shm);
        }
        out
    }

    /// Process ids of the iceoryx2 nodes of this prefix whose process still runs
    /// (iceoryx2's node monitoring; a node that cannot be checked counts as alive).
    pub fn live_node_pids(&self) -> Result<Vec<u32>, BusError> {
        set_log_level_from_env_or(LogLevel::Error);
        let config = self.iceoryx2_config()?;
        let mut pids = Vec::new();
        Node::<ipc::Service>::list(&config, |state| {
            let id = match &state {
                NodeState::Alive(view) => Some(*view.id()),
                NodeState::Inaccessible(id) | NodeState::Undefined(id) => Some(*id),
                NodeState::Dead(_) => None,
            };
            if let Some(id) = id {
                pids.push(
                    id.pid::<ipc::Service>()
                        .map(|p| u32::try_from(p.value()).unwrap_or(0))
                        .unwrap_or(0),
                );
            }
            CallbackProgression::Continue
        })
        .map_err(|e| BusError::new("cannot list the iceoryx2 nodes of the prefix", e))?;
        pids.sort_unstable();
        pids.dedup();
        Ok(pids)
    }

    /// Removes what dead processes of this prefix left behind (see
    /// [`BusConfig::prefix_files`]) and returns it; nothing if there is nothing.
    /// Refused, with the process ids, while a process of the prefix still runs
    /// (its files are in use); the caller makes sure no run holds the prefix
    /// ([`BusConfig::lock_prefix`]).
    pub fn remove_leftovers(&self) -> Result<Vec<Leftover>, BusError> {
        let found = self.prefix_files();
        if found.is_empty() {
            return Ok(found);
        }
        let live = self.live_node_pids()?;
        if !live.is_empty() {
            let p = self.iox_prefix.as_deref().unwrap_or("");
            return Err(BusError(format!(
                "the iceoryx2 prefix {p:?} has running processes ({}): its files are in use and were left in place",
                live.iter().map(|p| format!("process {p}")).collect::<Vec<_>>().join(", ")
            )));
        }
        for f in &found {
            let gone = if f.path.is_dir() {
                std::fs::remove_dir_all(&f.path)
            } else {
                std::fs::remove_file(&f.path)
            };
            match gone {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(BusError(format!("cannot remove {}: {e}", f.path.display()))),
            }
        }
        Ok(found)
    }
}

impl BusConfig {
    /// The directory of this prefix's iceoryx2 files other than its segments
    /// (`<private dir>/<prefix>`); `None` without a prefix.
    pub fn iox_root(&self) -> Option<std::path::PathBuf> {
        self.iox_prefix
            .as_ref()
            .map(|p| crate::private_dir_path().join(p))
    }

    /// The lock file of this prefix ([`BusConfig::lock_prefix`]:
    /// `<private dir>/<prefix>.lock`); `None` without a prefix.
    pub fn lock_path(&self) -> Option<std::path::PathBuf> {
        self.iox_prefix
            .as_ref()
            .map(|p| crate::private_dir_path().join(format!("{p}.lock")))
    }

    /// The iceoryx2 file prefix in `/dev/shm` (`lw_<prefix>_`, or iceoryx2's `iox2_`)
    /// and the root directory of its other files.
    fn file_prefix_and_root(&self) -> (String, String) {
        match &self.iox_prefix {
            Some(p) => (
                format!("lw_{p}_"),
                crate::private_dir_path().join(p).display().to_string(),
            ),
            None => ("iox2_".to_string(), "/tmp/iceoryx2".to_string()),
        }
    }

    /// Why a node of this prefix may fail to start, read off the files: a global
    /// management segment (`/dev/shm/<prefix>*.global_mgmt`) of another user, or
    /// one that is damaged (another size than iceoryx2's own, or another version
    /// word: anything but what iceoryx2 0.10.0 writes), or a root directory of
    /// another user; each named with its owner, with the way out. `None` when
    /// nothing looks wrong (or nothing can be read).
    pub fn diagnose_blocked_start(&self) -> Option<String> {
        use std::os::unix::fs::MetadataExt;
        let (start, root) = self.file_prefix_and_root();
        let me = crate::current_uid();
        let (env, clean) = match &self.iox_prefix {
            Some(p) => (
                format!("prefix {p:?}"),
                format!("leakwatch clean --prefix {p}, or "),
            ),
            None => ("iceoryx2's default prefix".to_string(), String::new()),
        };
        let way_out = format!(
            "once no process of this prefix runs, remove its files ({clean}rm -rf {root} /dev/shm/{start}*) or \
             start with another prefix (LEAKWATCH_IOX_PREFIX=...); see docs/security.md"
        );
        let mut found = Vec::new();
        for entry in std::fs::read_dir("/dev/shm").ok()?.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if !(name.starts_with(&start) && name.ends_with(".global_mgmt")) {
                continue;
            }
            let Ok(meta) = entry.metadata() else { continue };
            let what = format!("the management segment /dev/shm/{name} of {env}");
            if meta.uid() != me {
                found.push(format!(
                    "{what} belongs to another user (uid {}, mode {:o}; only that user or root can remove it)",
                    meta.uid(),
                    meta.mode() & 0o7777
                ));
            } else if let Some(damage) = mgmt_damage(&entry.path()) {
                found.push(format!("{what} is damaged ({damage}; owner uid {me}, this user)"));
            }
        }
        if let Ok(meta) = std::fs::metadata(&root) {
            if meta.uid() != me {
                found.push(format!(
                    "{root} belongs to another user (uid {}, mode {:o})",
                    meta.uid(),
                    meta.mode() & 0o7777
                ));
            }
        }
        if found.is_empty() {
            None
        } else {
            Some(format!("{}: {way_out}", found.join("; ")))
        }
    }
}

/// What is wrong with the global management segment at `path`, if anything:
/// a size other than [`GLOBAL_MGMT_BYTES`], or a first word other than
/// [`GLOBAL_MGMT_VERSION`] (read twice 50 ms apart: a node that is creating it
/// writes the word last).
fn mgmt_damage(path: &std::path::Path) -> Option<String> {
    let read = || -> Option<String> {
        let bytes = std::fs::read(path).ok()?;
        if bytes.len() as u64 != GLOBAL_MGMT_BYTES {
            return Some(format!(
                "{} bytes, iceoryx2 writes {GLOBAL_MGMT_BYTES}",
                bytes.len()
            ));
        }
        let word = u64::from_le_bytes(bytes.get(..8)?.try_into().ok()?);
        (word != GLOBAL_MGMT_VERSION).then(|| {
            format!("its version word is {word:#x}, iceoryx2 0.10.0 writes {GLOBAL_MGMT_VERSION:#x}")
        })
    };
    read()?;
    std::thread::sleep(std::time::Duration::from_millis(50));
    read()
}

/// A prefix owned by one run: an exclusive lock (`flock`) on
/// `<private dir>/<prefix>.lock` ([`crate::private_dir`]), released when it is dropped or the
/// process ends (however it ends). The file holds the owner's process id. A
/// dropped lock removes its file (a killed run leaves it, and the next run on
/// the prefix takes it over).
#[derive(Debug)]
pub struct PrefixLock {
    file: std::fs::File,
    /// The lock file.
    pub path: std::path::PathBuf,
}

impl Drop for PrefixLock {
    fn drop(&mut self) {
        // Removed while still locked: a run that opened this file before the
        // removal finds, once it has the lock, that the path no longer names its
        // file, and opens the path again (see `lock_prefix`).
        if same_file(&self.file, &self.path) {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// Whether `path` names the open `file` (same device and inode).
fn same_file(file: &std::fs::File, path: &std::path::Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::symlink_metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

impl BusConfig {
    /// Takes the ownership of this config's prefix for one run: a second run with
    /// the same prefix is refused (naming the owner's process id) instead of sharing,
    /// and later deleting, the first one's shared memory. Without a prefix there is
    /// nothing to own (an error: a run always has one).
    pub fn lock_prefix(&self) -> Result<PrefixLock, BusError> {
        use std::io::{Read, Seek, Write};
        use std::os::unix::fs::OpenOptionsExt;
        use std::os::unix::io::AsRawFd;
        let Some(p) = &self.iox_prefix else {
            return Err(BusError("a run needs an isolation prefix to own".into()));
        };
        validate_prefix(p)?;
        let path = crate::private_dir()?.join(format!("{p}.lock"));
        // A lock taken on a file its owner removed on release is not the prefix's
        // lock: open the path again (a few times; each retry means another run
        // released the prefix meanwhile).
        let mut tries = 0;
        let mut file = loop {
            let mut file = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .mode(0o600)
                .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC)
                .open(&path)
                .map_err(|e| BusError(format!("cannot open the prefix lock {}: {e}", path.display())))?;
            // SAFETY: flock on an open descriptor we own; no memory is passed.
            if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
                let mut owner = String::new();
                let _ = file.read_to_string(&mut owner);
                return Err(BusError(format!(
                    "the iceoryx2 prefix {p:?} is in use by another leakwatch run (process {}, lock {}): \
                     two runs on one prefix would share and then delete each other's shared memory; \
                     use another LEAKWATCH_IOX_PREFIX, or leave it unset for a private one",
                    owner.trim(),
                    path.display()
                )));
            }
            if same_file(&file, &path) {
                break file;
            }
            tries += 1;
            if tries >= 10 {
                return Err(BusError(format!(
                    "the prefix lock {} keeps being removed and made again by other runs",
                    path.display()
                )));
            }
        };
        let pid = std::process::id();
        let write = |f: &mut std::fs::File| -> std::io::Result<()> {
            f.set_len(0)?;
            f.rewind()?;
            writeln!(f, "{pid}")
        };
        write(&mut file)
            .map_err(|e| BusError(format!("cannot write the prefix lock {}: {e}", path.display())))?;
        Ok(PrefixLock { file, path })
    }
}

/// Size of the global management segment iceoryx2 0.10 writes, bytes (its
/// version word and the node id counter); a file of that name of another size
/// is damaged.
const GLOBAL_MGMT_BYTES: u64 = 16;

/// The first 8 bytes (little-endian) of a global management segment iceoryx2
/// 0.10.0 made: its `PackageVersion` (major << 32 | minor << 16 | patch); a
/// node of 0.10.0 refuses any other.
const GLOBAL_MGMT_VERSION: u64 = 10 << 16;

/// Checks an isolation prefix: 1 to [`MAX_PREFIX_LEN`] characters of
/// `A-Z a-z 0-9 _ -`; the error names the prefix, its length and the limit.
pub fn validate_prefix(p: &str) -> Result<(), BusError> {
    if p.is_empty()
        || !p
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
    {
        return Err(BusError(format!(
            "invalid iceoryx2 isolation prefix {p:?} (from {PREFIX_ENV}?): use 1 to {MAX_PREFIX_LEN} characters of A-Z a-z 0-9 _ -"
        )));
    }
    if p.len() > MAX_PREFIX_LEN {
        return Err(BusError(format!(
            "iceoryx2 isolation prefix {p:?} (from {PREFIX_ENV}?) has {} characters; at most {MAX_PREFIX_LEN} \
             work: iceoryx2 puts it twice into the path of a Unix socket \
             (<dir>/<prefix>/lw_<prefix>_<id of up to 39 digits>.event), which must fit 108 bytes",
            p.len()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
