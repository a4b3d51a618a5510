//! The `acquisition` process (its code is [`acquisition::shell`], so that `leakwatch stage acquisition`
//! runs the same process from the one installed binary).

#![forbid(unsafe_code)]

fn main() -> std::process::ExitCode {
    acquisition::shell::main(std::env::args_os())
}
