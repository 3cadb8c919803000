//! The `aeroshape` command-line program: parsing and dispatch (each subcommand family lives
//! in its own module) and the pictures ([`pictures`], drawn with [`plot`]). See `docs/cli.md` for the contract: exit
//! status 0 on success, 1 on a user error (one line on stderr naming the file, line or
//! entity), 2 on a usage error.
//!
//! This is the only crate that knows about clap, indicatif and plotters: the pipeline itself
//! is the library `aeroshape` (`Study`, case files, atomic output), which an MDO framework
//! embeds without compiling a command line or a plotting stack.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// `println!` that returns a failed write as an error (`?`, into `anyhow`) instead of
/// panicking: with `aeroshape … | head -1` the reader closes the pipe and the program stops
/// quietly ([`main`] exits 0 on a broken pipe). Use it for everything written to stdout.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($arg)*)?
    }};
}

mod case;
mod case_check;
mod constraints;
mod deform;
#[cfg(feature = "mpi")]
mod deform_mpi;
mod geom;
mod geom_import;
mod gradient;
mod mesh;
mod param;
mod pictures;
mod plot;
mod run;
#[cfg(feature = "mpi")]
mod run_mpi;
mod section;
mod surfgrid;

/// CAD-linked shape parametrisation and grid update for aerodynamic shape optimisation.
#[derive(Debug, Parser)]
#[command(name = "aeroshape", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Make a ready case from your own CAD and grid (`case init`).
    #[command(subcommand)]
    Case(case::CaseCmd),
    /// Geometric constraints (thickness, volume, area) of a case on the updated model, and
    /// their exact Jacobian with respect to the design variables.
    Constraints(constraints::ConstraintsArgs),
    /// Deform a volume mesh from prescribed boundary motion (spring analogy, paper §4).
    Deform(deform::DeformArgs),
    /// Inspect and check geometric databases (RON).
    #[command(subcommand)]
    Geom(geom::GeomCmd),
    /// The gradient dJ/d(design variables) from a flow adjoint's dJ/d(grid coordinates)
    /// (SU2's RESTART_ASCII or surface-sensitivity CSV): the chain's reverse product.
    Gradient(gradient::GradientArgs),
    /// Inspect grids (counts, markers, quality) and convert between .su2, .msh and .vtu.
    #[command(subcommand)]
    Mesh(mesh::MeshCmd),
    /// List design variables and apply a design vector to a case's geometry (paper §5).
    #[command(subcommand)]
    Param(param::ParamCmd),
    /// Run the whole chain for a case (paper Fig. 5): design vector → parametrisation →
    /// model update → surface-grid update → volume deformation; writes the deformed grid
    /// (.su2, .msh, .vtu), the baseline grid, the updated geometry, report.json and pictures.
    Run(run::RunArgs),
    /// Fit and build wing sections (thickness parameters of Eq. 39, camber B-spline; §6.1).
    #[command(subcommand)]
    Section(section::SectionCmd),
    /// Generate surface grids tied to the geometry (advancing front in the parametric
    /// planes, §2.2–2.3) and classify imported grids on a geometric database.
    #[command(subcommand)]
    Surfgrid(surfgrid::SurfgridCmd),
}

/// Runs the program and maps the outcome to the exit status of the CLI contract.
fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // --help and --version print and exit 0; usage errors exit 2.
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { 2 } else { 0 });
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of stdout went away (`| head`): nothing more to say to anyone.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        // Under mpirun: every rank has printed it already.
        #[cfg(feature = "mpi")]
        Err(e) if e.is::<deform_mpi::Reported>() => ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {}", one_line(&e));
            ExitCode::from(1)
        }
    }
}

/// A clap value parser for a library enum that has `FromStr` and a name per value (deform's
/// `SolverKind` and `Stiffness`): clap parses with the library's `FromStr` (so the program
/// and the case files take the same names, and a bad name gets the library's message), and
/// `--help` lists the names.
#[derive(Clone)]
struct NameParser<T> {
    names: Vec<&'static str>,
    parsed: std::marker::PhantomData<fn() -> T>,
}

impl<T> NameParser<T> {
    /// A parser whose possible values are `names`.
    fn new(names: impl IntoIterator<Item = &'static str>) -> Self {
        Self {
            names: names.into_iter().collect(),
            parsed: std::marker::PhantomData,
        }
    }
}

impl<T> clap::builder::TypedValueParser for NameParser<T>
where
    T: std::str::FromStr + Clone + Send + Sync + 'static,
    T::Err: std::fmt::Display,
{
    type Value = T;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<T, clap::Error> {
        let name = arg.map_or_else(|| "value".to_string(), |a| format!("'{a}'"));
        let s = value.to_string_lossy();
        s.parse::<T>().map_err(|e| {
            clap::Error::raw(
                clap::error::ErrorKind::InvalidValue,
                format!("invalid value '{s}' for {name}: {e}\n"),
            )
            .with_cmd(cmd)
        })
    }

    fn possible_values(
        &self,
    ) -> Option<Box<dyn Iterator<Item = clap::builder::PossibleValue> + '_>> {
        Some(Box::new(
            self.names
                .iter()
                .map(|&n| clap::builder::PossibleValue::new(n)),
        ))
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Case(cmd) => case::run(cmd),
        Command::Constraints(args) => constraints::run(args),
        Command::Deform(args) => deform::run(args),
        Command::Geom(cmd) => geom::run(cmd),
        Command::Gradient(args) => gradient::run(args),
        Command::Mesh(cmd) => mesh::run(cmd),
        Command::Param(cmd) => param::run(cmd),
        Command::Run(args) => run::run(args),
        Command::Section(cmd) => section::run(cmd),
        Command::Surfgrid(cmd) => surfgrid::run(cmd),
    }
}

/// True when writing to stdout failed because its reader closed the pipe.
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Flattens an error and its causes into a single line. A cause whose message the line
/// already holds is not repeated (the library errors show their typed source in their own
/// message and also return it from `Error::source`).
fn one_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let msg = cause.to_string();
        let msg = msg.split_whitespace().collect::<Vec<_>>().join(" ");
        if msg.is_empty() || line.contains(&msg) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&msg);
    }
    line
}

#[cfg(test)]
mod tests {
    use super::one_line;

    #[test]
    fn one_line_joins_the_causes_without_repeating_them() {
        let io = std::io::Error::other("no such file");
        let e = anyhow::Error::new(io).context("geometry.ron:\n  cannot read");
        assert_eq!(one_line(&e), "geometry.ron: cannot read: no such file");
        // A library error whose message already holds its source's message.
        let e = aeroshape::study::StudyError::Read {
            path: "g.ron".into(),
            source: std::io::Error::other("no such file"),
        };
        assert_eq!(one_line(&anyhow::Error::new(e)), "g.ron: no such file");
    }
}
