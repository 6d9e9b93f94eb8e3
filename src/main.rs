//! The `tensegrity` command line: everything is in `tensegrity_testbed::cli`.

fn main() -> std::process::ExitCode {
    tensegrity_testbed::cli::main()
}
