//! `aeroshape section`: fit the wing-section parametrisation of the paper's §6.1 (Eq. 39
//! thickness, B-spline camber) to airfoil coordinates, and build a section from parameters.

use std::io::BufReader;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::{Args, Subcommand};
use wingmaster::{Airfoil, FitOptions, SectionFit, SectionParams, fit};

use crate::plot::{Mark, Plot, Series, write_stack};
use aeroshape::fsio::{ensure_not_input, write_atomic};

/// Wing-section commands.
#[derive(Debug, Subcommand)]
pub enum SectionCmd {
    /// Fit the section parametrisation (ten thickness parameters of Eq. 39 plus a B-spline
    /// camber line) to coordinates in Selig or Lednicer format, minimising the normal
    /// distance of the points to the curve. Prints the parameters, the camber control points
    /// and the fit error (max and RMS normal distance, in chords).
    Fit(FitArgs),
    /// Build a section from a PARAMS.ron file (see docs/formats/section-ron.md) and write it
    /// in Selig format (normalised: leading edge at (0, 0), chord 1).
    Build(BuildArgs),
}

/// Arguments of `aeroshape section fit`.
#[derive(Debug, Args)]
pub struct FitArgs {
    /// Airfoil coordinates (Selig or Lednicer format).
    pub airfoil: PathBuf,
    /// Camber control points, including the two fixed end points (≥ 2; m − 2 are fitted).
    #[arg(long, default_value_t = 8, value_name = "N")]
    pub camber_points: usize,
    /// Extra thickness control points beyond the paper's P0..P8 (each adds x and z).
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub thickness_extra: usize,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Write the fitted section (Selig format, file coordinates) to this file.
    #[arg(long, value_name = "FITTED.dat")]
    pub out: Option<PathBuf>,
    /// Points per surface in --out (≥ 100; 2N + 1 points in all).
    #[arg(long, default_value_t = 120, value_name = "N")]
    pub points: usize,
    /// Also write the fitted parameters as PARAMS.ron (input of `section build`).
    #[arg(long, value_name = "PARAMS.ron")]
    pub params: Option<PathBuf>,
    /// Draw the input points, the fit, both control polygons and the error to a PNG.
    #[arg(long, value_name = "FIT.png")]
    pub plot: Option<PathBuf>,
}

/// Arguments of `aeroshape section build`.
#[derive(Debug, Args)]
pub struct BuildArgs {
    /// Section parameters (RON, see docs/formats/section-ron.md).
    pub params: PathBuf,
    /// Output coordinates (Selig format).
    #[arg(short, long, value_name = "OUT.dat")]
    pub output: PathBuf,
    /// Points per surface (≥ 100; 2N + 1 points in all).
    #[arg(long, default_value_t = 120, value_name = "N")]
    pub points: usize,
    /// Draw the section and its control polygons to a PNG.
    #[arg(long, value_name = "SECTION.png")]
    pub plot: Option<PathBuf>,
}

/// Runs a `section` subcommand.
pub fn run(cmd: SectionCmd) -> anyhow::Result<()> {
    match cmd {
        SectionCmd::Fit(a) => run_fit(&a),
        SectionCmd::Build(a) => run_build(&a),
    }
}

fn check_outputs(input: &Path, outs: &[&Option<PathBuf>]) -> anyhow::Result<()> {
    for o in outs.iter().filter_map(|o| o.as_ref()) {
        ensure_not_input(o, &[input]).map_err(anyhow::Error::msg)?;
    }
    Ok(())
}

fn run_fit(a: &FitArgs) -> anyhow::Result<()> {
    let shown = a.airfoil.display().to_string();
    check_outputs(&a.airfoil, &[&a.out, &a.plot, &a.params])?;
    anyhow::ensure!(
        a.points >= 100,
        "--points {}: at least 100 per surface",
        a.points
    );
    let file = std::fs::File::open(&a.airfoil).with_context(|| format!("{shown}: cannot open"))?;
    let airfoil = Airfoil::parse(BufReader::new(file), &shown)?;
    let opts = FitOptions::default()
        .with_camber_points(a.camber_points)
        .with_thickness_extra(a.thickness_extra);
    let f = fit(&airfoil, &opts).with_context(|| format!("{shown}: fit failed"))?;
    let sec = f.section()?;
    if let Some(out) = &a.out {
        let pts: Vec<[f64; 2]> = sec
            .sample(a.points)
            .into_iter()
            .map(|p| f.frame.to_global(p))
            .collect();
        let name = format!("{} (aeroshape section fit)", airfoil.name.trim());
        write_atomic(out, |w| wingmaster::write_selig(w, &name, &pts))?;
    }
    if let Some(p) = &a.params {
        let text = ron::ser::to_string_pretty(&f.params, ron::ser::PrettyConfig::default())?;
        write_atomic(p, |w| w.write_all(text.as_bytes()))?;
    }
    if let Some(png) = &a.plot {
        plot_fit(&airfoil.name, &f, png)?;
    }
    if a.json {
        outln!("{}", serde_json::to_string(&f.summary_json())?);
    } else {
        print_fit(&shown, &airfoil, &f)?;
    }
    Ok(())
}

fn print_fit(shown: &str, airfoil: &Airfoil, f: &SectionFit) -> anyhow::Result<()> {
    let t = &f.params.thickness;
    outln!(
        "airfoil: {} ({shown}, {} points)",
        airfoil.name.trim(),
        f.points.len()
    );
    for w in &airfoil.warnings {
        outln!("note: {w}");
    }
    outln!(
        "frame: leading edge ({:.6}, {:.6}), chord {:.6}, chord angle {:.4} deg",
        f.frame.le[0],
        f.frame.le[1],
        f.frame.chord,
        f.frame.angle.to_degrees()
    );
    outln!("thickness (Eq. 39, half-thickness, chords / radians):");
    let named = [
        ("r0", t.r0, "leading-edge radius"),
        ("z1", t.z1, "P1 = (0, z1)"),
        ("z2", t.z2, "ordinate of P2"),
        ("xtmax", t.xtmax, "position of max thickness"),
        ("tmax", t.tmax, "max thickness"),
        ("crv4", t.crv4, "d2z_t/dx2 at P4"),
        ("x6", t.x6, "P6 abscissa"),
        ("z6", t.z6, "P6 ordinate"),
        ("phi_te", t.phi_te, "trailing-edge angle"),
        ("d78", t.d78, "|P8 - P7|"),
    ];
    for (n, v, what) in named {
        outln!("  {n:<7} = {v:>12.6}   {what}");
    }
    if !t.extra.is_empty() {
        outln!("thickness_extra (x, z):");
        for e in &t.extra {
            outln!("  ({:.6}, {:.6})", e[0], e[1]);
        }
    }
    outln!("trailing-edge thickness: {:.6}", f.params.te_thickness);
    outln!("camber control points Q_j (x, z):");
    for q in &f.params.camber {
        outln!("  ({:.6}, {:.6})", q[0], q[1]);
    }
    outln!(
        "fit error (normal distance / chord): max {:.3e}, rms {:.3e} ({} design variables, {} iterations)",
        f.max_error,
        f.rms_error,
        f.n_design_variables,
        f.iterations
    );
    Ok(())
}

fn section_series(sec: &wingmaster::Section) -> Vec<Series> {
    let curve: Vec<(f64, f64)> = sec.sample(200).iter().map(|p| (p[0], p[1])).collect();
    let tp: Vec<(f64, f64)> = sec
        .thickness()
        .points()
        .iter()
        .map(|p| (p[0], p[1]))
        .collect();
    let cp: Vec<(f64, f64)> = sec.camber().points().iter().map(|p| (p[0], p[1])).collect();
    let camber_line: Vec<(f64, f64)> = (0..=200)
        .map(|k| {
            let x = k as f64 / 200.0;
            (x, sec.camber().z_ders(x)[0])
        })
        .collect();
    vec![
        Series::line("section", curve).color((31, 119, 180)),
        Series::polygon("thickness polygon P0..P8 (z_t)", tp).color((44, 160, 44)),
        Series::polygon("camber polygon Q_j", cp).color((214, 39, 40)),
        Series::line("camber line", camber_line)
            .color((214, 39, 40))
            .mark(Mark::Dashed)
            .size(1),
    ]
}

fn plot_fit(name: &str, f: &SectionFit, png: &Path) -> anyhow::Result<()> {
    let sec = f.section()?;
    let mut top = Plot::new(&format!(
        "{}: fit, max {:.2e} c, rms {:.2e} c ({} design variables)",
        name.trim(),
        f.max_error,
        f.rms_error,
        f.n_design_variables
    ))
    .labels("x / c", "z / c")
    .equal_aspect(true)
    .size(1400, 560);
    let mut s = section_series(&sec);
    let input: Vec<(f64, f64)> = f.points.iter().map(|p| (p[0], p[1])).collect();
    s.insert(
        1,
        Series::points("input points", input)
            .color((0, 0, 0))
            .size(3),
    );
    for x in s {
        top.push(x);
    }
    let mut bottom = Plot::new("normal distance of the input points from the fit")
        .labels("x / c", "signed normal distance / c")
        .size(1400, 320);
    let (mut up, mut lo) = (Vec::new(), Vec::new());
    for ((p, d), s) in f.points.iter().zip(&f.distances).zip(&f.sigma) {
        if *s >= 0.0 {
            up.push((p[0], *d));
        } else {
            lo.push((p[0], *d));
        }
    }
    bottom.push(
        Series::line("upper surface", up.clone())
            .color((31, 119, 180))
            .size(1),
    );
    bottom.push(Series::points("", up).color((31, 119, 180)).size(2));
    bottom.push(
        Series::line("lower surface", lo.clone())
            .color((255, 127, 14))
            .size(1),
    );
    bottom.push(Series::points("", lo).color((255, 127, 14)).size(2));
    write_stack(png, &[top, bottom])
}

fn run_build(a: &BuildArgs) -> anyhow::Result<()> {
    let shown = a.params.display().to_string();
    ensure_not_input(&a.output, &[&a.params]).map_err(anyhow::Error::msg)?;
    if let Some(p) = &a.plot {
        ensure_not_input(p, &[&a.params]).map_err(anyhow::Error::msg)?;
    }
    anyhow::ensure!(
        a.points >= 100,
        "--points {}: at least 100 per surface",
        a.points
    );
    let text =
        std::fs::read_to_string(&a.params).with_context(|| format!("{shown}: cannot read"))?;
    let params: SectionParams = ron::from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "{shown}:{}:{}: {}",
            e.span.start.line,
            e.span.start.col,
            e.code
        )
    })?;
    let sec = params.build().with_context(|| shown.clone())?;
    let pts = sec.sample(a.points);
    let name = if params.name.trim().is_empty() {
        "aeroshape section".to_string()
    } else {
        params.name.clone()
    };
    write_atomic(&a.output, |w| wingmaster::write_selig(w, &name, &pts))?;
    if let Some(png) = &a.plot {
        let mut p = Plot::new(&name)
            .labels("x / c", "z / c")
            .equal_aspect(true)
            .size(1400, 560);
        for s in section_series(&sec) {
            p.push(s);
        }
        p.write_png(png)?;
    }
    Ok(())
}
