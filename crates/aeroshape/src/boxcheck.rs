//! The design box checked as a whole ([`check_box`]): `case init` checks each variable alone
//! at either bound, but an optimiser moves them together. The check samples combinations —
//! the box's corners (all of them up to [`BoxCheckOptions::max_corners`], else a random
//! subset) and a Latin hypercube of [`BoxCheckOptions::samples`] vectors — runs the chain on
//! each, and, where one fails, shrinks the box about the initial design: first by bisection
//! on a common scale `s` until every sample passes, then each variable in turn grown back
//! towards its full range (bisection on its own scale `s_i ∈ [s, 1]`) as far as every sample
//! still passes, so that the variables that do not take part in a failure keep their
//! bounds.
//!
//! A sample is a point `ξ ∈ [−1, 1]ⁿ` of the unit box; at scales `s_i` it is the design vector
//! `x_i = x0_i + s_i ξ_i (u_i − x0_i)` for `ξ_i ≥ 0` and `x0_i + s_i |ξ_i| (l_i − x0_i)` below, with
//! `l, u` the variable's bounds and `x0` the initial design. It passes when the chain
//! succeeds and inverts no cell (cells already invalid in the baseline grid are not counted,
//! as in the deformation's guard).
//!
//! The samples are drawn by a xorshift generator from [`BoxCheckOptions::seed`], so a check
//! is repeatable. Which variables fail together is told by [`PairTable`]: for every pair
//! `(i, j)`, the valid fraction of the full-box samples with both `|ξ_i|` and `|ξ_j|` at
//! least ½ (the diagonal: `|ξ_i| ≥ ½` alone).

use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;
use serde::Serialize;

use crate::Study;

/// What [`check_box`] samples and how far it shrinks.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxCheckOptions {
    /// Latin-hypercube samples (besides the corners).
    pub samples: usize,
    /// At most this many corners (all `2ⁿ` when they are fewer, else this many drawn at
    /// random).
    pub max_corners: usize,
    /// Seed of the generator.
    pub seed: u64,
    /// Bisection steps on the common scale once the full box fails (the scale found is
    /// within `2^-steps` of the largest that passes).
    pub shrink_steps: usize,
    /// Bisection steps on each variable's own scale as it is grown back, after the try at
    /// its full range (0: that try only).
    pub grow_steps: usize,
}

impl Default for BoxCheckOptions {
    fn default() -> Self {
        Self {
            samples: 40,
            max_corners: 16,
            seed: 1,
            shrink_steps: 4,
            grow_steps: 4,
        }
    }
}

/// How a sample was drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum SampleKind {
    /// A corner of the box.
    Corner,
    /// A Latin-hypercube point.
    Hypercube,
}

/// One sample's outcome at one scale.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SampleResult {
    /// Its index in [`BoxCheck::unit`].
    pub sample: usize,
    /// The design vector evaluated.
    pub x: Vec<f64>,
    /// Whether the chain succeeded and no cell was inverted.
    pub valid: bool,
    /// Cells inverted beyond the baseline's (0 when the chain failed before the grid).
    pub inverted: usize,
    /// Smallest cell quality (NaN when the chain failed).
    pub min_quality: f64,
    /// What failed, in words.
    pub failure: Option<String>,
}

/// The samples evaluated at one set of scales.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Round {
    /// The common scale of the box, or, in a round that grows one variable back, the
    /// common scale found.
    pub scale: f64,
    /// The variable grown back in this round and its scale (`None`: a round of the common
    /// scale).
    pub grown: Option<(usize, f64)>,
    /// The samples evaluated (a shrinking round stops at its first failure).
    pub results: Vec<SampleResult>,
}

impl Round {
    /// Whether every sample evaluated passed.
    pub fn passed(&self) -> bool {
        self.results.iter().all(|r| r.valid)
    }
}

/// Valid fractions per pair of variables, over the full-box samples (see the module doc).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairTable {
    /// Variable names, in registry order.
    pub names: Vec<String>,
    /// `fraction[i][j]`: valid fraction of the samples far out in both `i` and `j` (NaN
    /// when there is none).
    pub fraction: Vec<Vec<f64>>,
    /// `count[i][j]`: how many samples that is.
    pub count: Vec<Vec<usize>>,
}

impl PairTable {
    /// The pairs `(i, j)`, `i < j`, whose fraction is below the smaller of the two
    /// variables' own fractions, worst first.
    pub fn failing_together(&self) -> Vec<(usize, usize, f64)> {
        let n = self.names.len();
        let mut out = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                let f = self.fraction[i][j];
                let alone = self.fraction[i][i].min(self.fraction[j][j]);
                if f < 1.0 && f < alone {
                    out.push((i, j, f));
                }
            }
        }
        out.sort_by(|a, b| a.2.total_cmp(&b.2));
        out
    }
}

/// The outcome of [`check_box`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BoxCheck {
    /// The samples in the unit box, one `ξ` per sample.
    pub unit: Vec<Vec<f64>>,
    /// How each was drawn.
    pub kinds: Vec<SampleKind>,
    /// The rounds, the full box first.
    pub rounds: Vec<Round>,
    /// The largest common scale at which every sample passed (1: the whole box).
    pub scale: f64,
    /// Each variable's scale once grown back (each at least [`BoxCheck::scale`]); every
    /// sample passes with these.
    pub scales: Vec<f64>,
    /// Which variables fail together, from the full-box round.
    pub pairs: PairTable,
}

impl BoxCheck {
    /// The bounds `(lower, upper)` of each variable in the box of [`BoxCheck::scales`].
    pub fn bounds(&self, study: &Study) -> Vec<(f64, f64)> {
        let x0 = study.initial();
        study
            .registry()
            .variables()
            .iter()
            .zip(x0.iter().zip(&self.scales))
            .map(|(v, (&x, &s))| (x + s * (v.lower - x), x + s * (v.upper - x)))
            .collect()
    }

    /// Sets the bounds of `case` (the case `study` was built from) to
    /// [`BoxCheck::bounds`], variable by variable.
    pub fn apply_bounds(&self, study: &Study, case: &mut crate::case::Case) {
        let bounds = self.bounds(study);
        let vars = study.registry().variables();
        for m in &mut case.parametrisation.modifiers {
            for v in crate::init::space::variables_mut(m) {
                if let Some(k) = vars.iter().position(|w| w.name == v.name) {
                    (v.lower, v.upper) = bounds[k];
                }
            }
        }
    }

    /// Whether every bound is kept (the whole box passed).
    pub fn whole_box(&self) -> bool {
        self.scales.iter().all(|&s| s == 1.0)
    }
}

/// Checks the box of `study`'s design variables (module doc); `progress(done, total)` is
/// called after every evaluation of a round.
pub fn check_box(
    study: &Study,
    opts: &BoxCheckOptions,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> BoxCheck {
    let n = study.registry().variables().len();
    let mut rng = XorShiftRng::seed_from_u64(opts.seed);
    let (unit, kinds) = draw(n, opts, &mut rng);
    let order: Vec<usize> = (0..unit.len()).collect();
    let full = round(study, &unit, &vec![1.0; n], None, &order, false, progress);
    let pairs = pair_table(study, &unit, &full);
    // the samples that failed before are tried first; a shrinking round stops at the first
    // failure
    let mut failed: Vec<usize> = full
        .results
        .iter()
        .filter(|r| !r.valid)
        .map(|r| r.sample)
        .collect();
    let mut rounds = vec![full];
    if failed.is_empty() {
        study.forget_warm_start();
        return BoxCheck {
            unit,
            kinds,
            rounds,
            scale: 1.0,
            scales: vec![1.0; n],
            pairs,
        };
    }
    let mut try_round =
        |scales: &[f64], grown, failed: &mut Vec<usize>, rounds: &mut Vec<Round>| {
            let mut order = failed.clone();
            order.extend((0..unit.len()).filter(|k| !failed.contains(k)));
            let r = round(study, &unit, scales, grown, &order, true, progress);
            let passed = r.passed();
            for f in r.results.iter().filter(|r| !r.valid) {
                if !failed.contains(&f.sample) {
                    failed.insert(0, f.sample);
                }
            }
            rounds.push(r);
            passed
        };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..opts.shrink_steps {
        let mid = 0.5 * (lo + hi);
        if try_round(&vec![mid; n], None, &mut failed, &mut rounds) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let mut scales = vec![lo; n];
    if lo > 0.0 {
        // each variable grown back in turn, the most often valid first
        let mut by_fraction: Vec<usize> = (0..n).collect();
        by_fraction.sort_by(|&a, &b| pairs.fraction[b][b].total_cmp(&pairs.fraction[a][a]));
        for i in by_fraction {
            let (mut lo_i, mut hi_i) = (lo, 1.0);
            let mut trial = scales.clone();
            trial[i] = 1.0;
            if try_round(&trial, Some((i, 1.0)), &mut failed, &mut rounds) {
                lo_i = 1.0;
            } else {
                for _ in 0..opts.grow_steps {
                    let mid = 0.5 * (lo_i + hi_i);
                    trial[i] = mid;
                    if try_round(&trial, Some((i, mid)), &mut failed, &mut rounds) {
                        lo_i = mid;
                    } else {
                        hi_i = mid;
                    }
                }
            }
            scales[i] = lo_i;
        }
    }
    for r in &mut rounds[1..] {
        if r.grown.is_some() {
            r.scale = lo;
        }
    }
    study.forget_warm_start();
    BoxCheck {
        unit,
        kinds,
        rounds,
        scale: lo,
        scales,
        pairs,
    }
}

/// The corners and the Latin hypercube in the unit box `[−1, 1]ⁿ`.
fn draw(
    n: usize,
    opts: &BoxCheckOptions,
    rng: &mut XorShiftRng,
) -> (Vec<Vec<f64>>, Vec<SampleKind>) {
    let mut unit = Vec::new();
    let all_corners = n < 63 && (1u64 << n) <= opts.max_corners as u64;
    let corners = if all_corners {
        1usize << n
    } else {
        opts.max_corners
    };
    let mut seen = std::collections::BTreeSet::new();
    for c in 0..corners {
        let bits: Vec<bool> = if all_corners {
            (0..n).map(|i| c >> i & 1 == 1).collect()
        } else {
            (0..n).map(|_| rng.next_u64() >> 63 == 1).collect()
        };
        if seen.insert(bits.clone()) {
            unit.push(bits.iter().map(|&b| if b { 1.0 } else { -1.0 }).collect());
        }
    }
    let mut kinds = vec![SampleKind::Corner; unit.len()];
    let m = opts.samples;
    // one random permutation of the m strata per variable, a uniform point in each stratum
    let mut strata: Vec<Vec<usize>> = (0..n)
        .map(|_| {
            let mut p: Vec<usize> = (0..m).collect();
            for k in (1..m).rev() {
                p.swap(k, uniform_index(rng, k + 1));
            }
            p
        })
        .collect();
    for k in 0..m {
        let xi = strata
            .iter_mut()
            .map(|p| -1.0 + 2.0 * (p[k] as f64 + unit_f64(rng)) / m as f64)
            .collect();
        unit.push(xi);
        kinds.push(SampleKind::Hypercube);
    }
    (unit, kinds)
}

/// A uniform number in [0, 1) from the top 53 bits.
fn unit_f64(rng: &mut XorShiftRng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// A uniform index in `0..n` (`n ≥ 1`).
fn uniform_index(rng: &mut XorShiftRng, n: usize) -> usize {
    ((unit_f64(rng) * n as f64) as usize).min(n - 1)
}

/// The design vector of the unit sample `xi` at the scales `scales`, one per variable
/// (module doc).
pub fn design_vector(study: &Study, xi: &[f64], scales: &[f64]) -> Vec<f64> {
    let x0 = study.initial();
    study
        .registry()
        .variables()
        .iter()
        .zip(x0.iter().zip(xi.iter().zip(scales)))
        .map(|(v, (&x, (&t, &s)))| {
            let far = if t >= 0.0 { v.upper } else { v.lower };
            x + s * t.abs() * (far - x)
        })
        .collect()
}

/// Evaluates the samples `order` at `scales`; with `stop`, up to the first failure.
fn round(
    study: &Study,
    unit: &[Vec<f64>],
    scales: &[f64],
    grown: Option<(usize, f64)>,
    order: &[usize],
    stop: bool,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Round {
    let label = match grown {
        Some((i, s)) => format!("{} grown to {s:.4}", study.registry().variables()[i].name),
        None => format!("box at scale {:.4}", scales.first().copied().unwrap_or(1.0)),
    };
    let mut results = Vec::new();
    for (done, &k) in order.iter().enumerate() {
        let r = evaluate(study, k, design_vector(study, &unit[k], scales));
        let failed = !r.valid;
        results.push(r);
        progress(&label, done + 1, order.len());
        if stop && failed {
            break;
        }
    }
    Round {
        scale: scales.first().copied().unwrap_or(1.0),
        grown,
        results,
    }
}

/// One sample through the chain, from the baseline (no warm start: the samples are far
/// apart).
fn evaluate(study: &Study, sample: usize, x: Vec<f64>) -> SampleResult {
    study.forget_warm_start();
    match study.evaluate(&x) {
        Ok(ev) => {
            let was = ev.report.quality_before.inverted;
            let now = ev.report.quality_after.inverted;
            let inverted = now.saturating_sub(was);
            SampleResult {
                sample,
                x,
                valid: now <= was,
                inverted,
                min_quality: ev.report.quality_after.min,
                failure: (now > was).then(|| format!("{inverted} inverted cells")),
            }
        }
        Err(e) => SampleResult {
            sample,
            x,
            valid: false,
            inverted: 0,
            min_quality: f64::NAN,
            failure: Some(e.to_string()),
        },
    }
}

/// The valid fractions per pair over the full-box round `full`.
fn pair_table(study: &Study, unit: &[Vec<f64>], full: &Round) -> PairTable {
    let names: Vec<String> = study
        .registry()
        .variables()
        .iter()
        .map(|v| v.name.clone())
        .collect();
    let n = names.len();
    let mut count = vec![vec![0usize; n]; n];
    let mut valid = vec![vec![0usize; n]; n];
    for r in &full.results {
        let xi = &unit[r.sample];
        for i in (0..n).filter(|&i| xi[i].abs() >= 0.5) {
            for j in (0..n).filter(|&j| xi[j].abs() >= 0.5) {
                count[i][j] += 1;
                valid[i][j] += usize::from(r.valid);
            }
        }
    }
    let fraction = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| match count[i][j] {
                    0 => f64::NAN,
                    c => valid[i][j] as f64 / c as f64,
                })
                .collect()
        })
        .collect();
    PairTable {
        names,
        fraction,
        count,
    }
}
