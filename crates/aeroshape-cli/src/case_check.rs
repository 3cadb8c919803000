//! `aeroshape case check`: the design box checked as a whole (`aeroshape::boxcheck`): the
//! corners and a Latin hypercube through the chain, the box shrunk about the initial design
//! until every sample passes, the table of bounds, the variables that fail together and a
//! picture of the valid fraction per pair of variables.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;
use plotters::prelude::*;

use aeroshape::Study;
use aeroshape::boxcheck::{BoxCheck, BoxCheckOptions, PairTable, check_box};

/// Arguments of `case check`.
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The case file.
    pub case: PathBuf,
    /// Latin-hypercube samples besides the corners.
    #[arg(long, default_value_t = 40, value_name = "N")]
    pub samples: usize,
    /// At most this many corners of the box (all of them when there are fewer).
    #[arg(long, default_value_t = 16, value_name = "N")]
    pub corners: usize,
    /// Seed of the samples (the same seed draws the same samples).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Bisection steps on the box's common scale once the whole box fails.
    #[arg(long, default_value_t = 4, value_name = "N")]
    pub shrink_steps: usize,
    /// Bisection steps on each variable's scale as it is grown back from the common one
    /// (after the try at its full range).
    #[arg(long, default_value_t = 4, value_name = "N")]
    pub grow_steps: usize,
    /// Write the case with the shrunk bounds here (a new file; the input is not changed).
    #[arg(short, long, value_name = "CASE.ron")]
    pub output: Option<PathBuf>,
    /// Draw the valid fraction per pair of variables to this PNG.
    #[arg(long, value_name = "PNG")]
    pub picture: Option<PathBuf>,
    /// Write every sample's outcome as JSON here.
    #[arg(long, value_name = "JSON")]
    pub json: Option<PathBuf>,
}

/// Runs `case check`.
pub fn check(a: &CheckArgs) -> anyhow::Result<()> {
    if a.samples == 0 && a.corners == 0 {
        bail!("--samples and --corners are both 0: nothing to check");
    }
    for out in [&a.output, &a.picture, &a.json].into_iter().flatten() {
        aeroshape::fsio::ensure_not_input(out, &[&a.case]).map_err(anyhow::Error::msg)?;
    }
    let study = Study::load(&a.case)?;
    if study.registry().variables().is_empty() {
        bail!("{}: the case has no design variables", a.case.display());
    }
    let opts = BoxCheckOptions {
        samples: a.samples,
        max_corners: a.corners,
        seed: a.seed,
        shrink_steps: a.shrink_steps,
        grow_steps: a.grow_steps,
    };
    let bar = bar();
    let r = check_box(&study, &opts, &mut |what, done, total| {
        if let Some(b) = &bar {
            b.set_message(format!("{what}: {done}/{total}"));
        }
    });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    print(&study, &r)?;
    if let Some(p) = &a.json {
        aeroshape::fsio::write_atomic(p, |w| {
            serde_json::to_writer_pretty(&mut *w, &r).map_err(std::io::Error::other)
        })
        .with_context(|| format!("{}: cannot write", p.display()))?;
        outln!("wrote {}", p.display());
    }
    if let Some(p) = &a.picture {
        pair_picture(p, &r.pairs)?;
        outln!("wrote {}", p.display());
    }
    if let Some(p) = &a.output {
        write_case(&study, &r, &a.case, p)?;
        outln!("wrote {} (the shrunk bounds)", p.display());
    }
    Ok(())
}

fn bar() -> Option<indicatif::ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let b = indicatif::ProgressBar::new_spinner();
    b.enable_steady_tick(std::time::Duration::from_millis(120));
    Some(b)
}

fn print(study: &Study, r: &BoxCheck) -> anyhow::Result<()> {
    let full = &r.rounds[0];
    let bad = full.results.iter().filter(|s| !s.valid).count();
    outln!(
        "whole box: {} of {} samples valid ({} corners, {} Latin hypercube)",
        full.results.len() - bad,
        full.results.len(),
        r.kinds
            .iter()
            .filter(|k| **k == aeroshape::boxcheck::SampleKind::Corner)
            .count(),
        r.kinds
            .iter()
            .filter(|k| **k == aeroshape::boxcheck::SampleKind::Hypercube)
            .count()
    );
    for s in full.results.iter().filter(|s| !s.valid).take(8) {
        outln!(
            "  sample {:>3} ({:?}): {}",
            s.sample,
            r.kinds[s.sample],
            s.failure.as_deref().unwrap_or("invalid")
        );
    }
    let names = &r.pairs.names;
    for round in &r.rounds[1..] {
        let what = match round.grown {
            Some((i, s)) => format!("{} grown back to {s:.4}", names[i]),
            None => format!("scale {:.4}", round.scale),
        };
        outln!(
            "{what}: {}",
            if round.passed() {
                format!("all {} samples valid", round.results.len())
            } else {
                let f = round.results.iter().find(|s| !s.valid);
                format!(
                    "sample {} fails",
                    f.map_or(String::new(), |s| s.sample.to_string())
                )
            }
        );
    }
    if r.whole_box() {
        outln!("the whole box passes");
    } else if r.scale == 0.0 {
        outln!(
            "the box fails even at {} of its size about the initial design",
            0.5f64.powi(r.rounds.len() as i32 - 1)
        );
    } else {
        outln!(
            "the box shrunk about the initial design: common scale {:.4}, then each variable \
             grown back as far as every sample passes (column scale)",
            r.scale
        );
    }
    outln!(
        "  {:<32} {:>11} {:>11} {:>11} {:>11} {:>7} {:>8}",
        "name",
        "lower",
        "upper",
        "new lower",
        "new upper",
        "scale",
        "valid"
    );
    let vars = study.registry().variables();
    for (i, (v, (lo, hi))) in vars.iter().zip(r.bounds(study)).enumerate() {
        outln!(
            "  {:<32} {:>11.4e} {:>11.4e} {:>11.4e} {:>11.4e} {:>7.4} {:>8}",
            v.name,
            v.lower,
            v.upper,
            lo,
            hi,
            r.scales[i],
            fraction(r.pairs.fraction[i][i])
        );
    }
    let together = r.pairs.failing_together();
    if !together.is_empty() {
        outln!("fail together (valid fraction with both far out, below either alone):");
        for (i, j, f) in together.iter().take(10) {
            outln!(
                "  {} + {}: {} of {}",
                r.pairs.names[*i],
                r.pairs.names[*j],
                fraction(*f),
                r.pairs.count[*i][*j]
            );
        }
    }
    Ok(())
}

fn fraction(f: f64) -> String {
    if f.is_nan() {
        "-".into()
    } else {
        format!("{:.0} %", 100.0 * f)
    }
}

/// The case `input` with the bounds of the shrunk box, at `out`; the geometry and grid paths
/// are made absolute when `out` is in another folder.
fn write_case(study: &Study, r: &BoxCheck, input: &Path, out: &Path) -> anyhow::Result<()> {
    let mut case = study.case().clone();
    r.apply_bounds(study, &mut case);
    let dir = |p: &Path| {
        p.parent()
            .map(Path::to_path_buf)
            .unwrap_or_default()
            .canonicalize()
            .ok()
    };
    let (from, to) = (dir(input), dir(out));
    if from != to
        && let Some(from) = from
    {
        case.geometry = from.join(&case.geometry).display().to_string();
        case.grid = case.grid.map(|g| from.join(g).display().to_string());
    }
    let text = format!(
        "// Made by `aeroshape case check` from {}: bounds shrunk (common scale {:.4}, then\n\
         // each variable grown back) until every sampled combination gives a valid grid.\n{}\n",
        input.display(),
        r.scale,
        case.to_ron_string()
    );
    aeroshape::fsio::write_atomic(out, |w| w.write_all(text.as_bytes()))
        .with_context(|| format!("{}: cannot write", out.display()))?;
    Ok(())
}

/// The valid fraction per pair of variables as a coloured matrix (red 0 %, green 100 %, grey:
/// no sample far out in both), atomically.
fn pair_picture(path: &Path, t: &PairTable) -> anyhow::Result<()> {
    let n = t.names.len();
    let cell = 48u32;
    let (left, top) = (220u32, 70u32);
    let (w, h) = (left + cell * n as u32 + 40, top + cell * n as u32 + 40);
    let tmp = aeroshape::fsio::temp_beside(path)
        .with_context(|| format!("{}: cannot create a temporary file", path.display()))?;
    let e = |e: DrawingAreaErrorKind<_>| anyhow::anyhow!("{}: {e}", path.display());
    {
        crate::plot::register_font();
        let root = BitMapBackend::new(tmp.path(), (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(e)?;
        let font = ("sans-serif", 14).into_font();
        root.draw(&Text::new(
            "valid samples (%), both variables far out (|ξ| ≥ ½); grey: none",
            (10, 10),
            ("sans-serif", 18).into_font(),
        ))
        .map_err(e)?;
        for (i, name) in t.names.iter().enumerate() {
            let y = (top + cell * i as u32 + cell / 2 - 7) as i32;
            root.draw(&Text::new(
                format!("{} {}", i + 1, short(name)),
                (10, y),
                font.clone(),
            ))
            .map_err(e)?;
            let x = (left + cell * i as u32 + 4) as i32;
            root.draw(&Text::new(
                format!("{}", i + 1),
                (x + 12, top as i32 - 20),
                font.clone(),
            ))
            .map_err(e)?;
            for j in 0..n {
                let (x0, y0) = (
                    (left + cell * j as u32) as i32,
                    (top + cell * i as u32) as i32,
                );
                let f = t.fraction[i][j];
                let color = if f.is_nan() {
                    RGBColor(200, 200, 200)
                } else {
                    RGBColor((255.0 * (1.0 - f)) as u8, (200.0 * f) as u8, 60)
                };
                root.draw(&Rectangle::new(
                    [(x0, y0), (x0 + cell as i32 - 2, y0 + cell as i32 - 2)],
                    color.filled(),
                ))
                .map_err(e)?;
                if !f.is_nan() {
                    root.draw(&Text::new(
                        format!("{:.0}", 100.0 * f),
                        (x0 + 10, y0 + 16),
                        font.clone().color(&WHITE),
                    ))
                    .map_err(e)?;
                }
            }
        }
        root.present().map_err(e)?;
    }
    tmp.persist(path)
        .map_err(|e| e.error)
        .with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(())
}

/// A variable's name with its row number cut to fit the label column.
fn short(name: &str) -> String {
    if name.chars().count() > 26 {
        format!("{}…", name.chars().take(25).collect::<String>())
    } else {
        name.to_string()
    }
}
