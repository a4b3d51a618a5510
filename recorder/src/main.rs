//! The `recorder` process (its code is [`recorder::shell`], so that `leakwatch stage recorder`
//! runs the same process from the one installed binary).

#![forbid(unsafe_code)]

fn main() -> std::process::ExitCode {
    recorder::shell::main(std::env::args_os())
}
