//! The `estimator` process (its code is [`estimator::shell`], so that `leakwatch stage estimator`
//! runs the same process from the one installed binary).

#![forbid(unsafe_code)]

fn main() -> std::process::ExitCode {
    estimator::shell::main(std::env::args_os())
}
