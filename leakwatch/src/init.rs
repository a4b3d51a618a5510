//! `leakwatch init`: writes [`config::init::template`] for the user to fill in.

use std::path::Path;

/// The command: writes the template to `out` (an existing file only with `force`).
pub fn command(single_rod: bool, out: &Path, force: bool) -> Result<(), String> {
    let text = config::init::template(&config::init::example(single_rod));
    crate::out::write(out, text.as_bytes(), force, &[])?;
    eprintln!(
        "wrote {}: an example {} rig's datasheet; replace its values with your rig's (docs/rig.md), \
         then check it with `leakwatch config --check {}`",
        out.display(),
        if single_rod { "single-rod" } else { "double-rod" },
        out.display()
    );
    Ok(())
}
