//! The `aeroshape` command-line program. See `docs/cli.md` for the contract: exit status 0
//! on success, 1 on a user error (one line on stderr naming the file, line or entity), 2 on
//! a usage error.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
