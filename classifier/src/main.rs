//! The `classifier` process (its code is [`classifier::shell`], so that `leakwatch stage classifier`
//! runs the same process from the one installed binary).

#![forbid(unsafe_code)]

fn main() -> std::process::ExitCode {
    classifier::shell::main(std::env::args_os())
}
