//! Every output of the command line goes through here: files and directories
//! through [`dataset::output`] (no symbolic link followed, no file replaced
//! without `--force`, never an input), standard output with its errors
//! reported (a full disk or a closed pipe is an error, not a panic).

use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path`; an existing file only if `force`, none of `inputs` ever.
pub fn write(path: &Path, bytes: &[u8], force: bool, inputs: &[&Path]) -> Result<(), String> {
    dataset::output::write_file(path, bytes, force, inputs).map_err(|e| dataset::output::message(path, &e))
}

/// Opens `path` for writing as [`write()`] would.
pub fn create(path: &Path, force: bool, inputs: &[&Path]) -> Result<std::fs::File, String> {
    dataset::output::create_file(path, force, inputs).map_err(|e| dataset::output::message(path, &e))
}

/// Checks that `path` may be written (see [`write()`]) without touching it.
pub fn check(path: &Path, force: bool, inputs: &[&Path]) -> Result<(), String> {
    dataset::output::check_replaceable(path, force, inputs).map_err(|e| dataset::output::message(path, &e))
}

/// Creates the output directory `dir` (not a symbolic link).
pub fn dir(dir: &Path) -> Result<(), String> {
    dataset::output::create_dir(dir).map_err(|e| format!("cannot create directory {}: {e}", dir.display()))
}

/// Renders `fig` and writes it as a PNG file (see [`write()`]).
pub fn png(fig: &plot::Figure, path: &Path, force: bool, inputs: &[&Path]) -> Result<(), String> {
    let img = plot::render(fig).map_err(|e| format!("{}: {e}", path.display()))?;
    let bytes = plot::encode_png(&img).map_err(|e| format!("{}: {e}", path.display()))?;
    write(path, &bytes, force, inputs)
}

/// Renders `fig` and writes it as an SVG file when `path` ends in `.svg`, else
/// as a PNG file (see [`write()`]).
pub fn figure(fig: &plot::Figure, path: &Path, force: bool, inputs: &[&Path]) -> Result<(), String> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("svg")) {
        let svg = plot::render_svg(fig).map_err(|e| format!("{}: {e}", path.display()))?;
        write(path, svg.as_bytes(), force, inputs)
    } else {
        png(fig, path, force, inputs)
    }
}

/// Writes `text` to standard output and flushes it. (A standard output closed
/// with `>&-` is reopened on /dev/null by the Rust runtime at start: writes to it
/// succeed and are lost.)
pub fn stdout(text: &str) -> Result<(), String> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|_| out.flush())
        .map_err(|e| format!("cannot write to standard output: {e}"))
}

/// `println!` that returns the error (`cannot write to standard output: ...`)
/// from the enclosing function instead of panicking.
#[macro_export]
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::out::stdout(&format!("{}\n", format_args!($($arg)*)))?
    };
}
pub use crate::outln;
