//! Binding a [`WingMasterSpec`] to a support surface: key sections sampled and fitted, the
//! stations' frames and interpolation weights, the planform variables located
//! ([`WingMasterSpec::bind`]); the master sources of a parametrisation
//! ([`master_sources`]).

use super::*;

/// Samples one face at normalised (section s, span t), its reversals applied.
fn sample_face(db: &GeomDb, f: &SectionFace, s: f64, t: f64) -> Point3 {
    let surf = db.surface(f.surface);
    let ([u0, u1], [v0, v1]) = surf.domain();
    let s = if f.reverse_section { 1.0 - s } else { s };
    let t = if f.reverse_span { 1.0 - t } else { t };
    let (a, b) = match f.spanwise {
        Param::V => (s, t),
        Param::U => (t, s),
    };
    surf.point(u0 + a * (u1 - u0), v0 + b * (v1 - v0))
}

impl WingMasterSpec {
    /// Parses a spec from RON (with `param`'s RON options); `path` names the file.
    pub fn from_ron_str(text: &str, path: &str) -> Result<Self> {
        param::ron_from_str(text, path).map_err(|e| err(e.to_string()))
    }

    /// The spec as pretty RON.
    pub fn to_ron_string(&self) -> String {
        param::ron_to_string(self)
    }

    /// Every variable name the spec uses, in first-use order (planform sweep, dihedral,
    /// span, then each key section: twist, chord, shift x/y/z, thickness, camber), each once.
    /// A master modifier may list its variables in any order.
    pub fn variable_names(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        let mut push = |n: &Option<String>| {
            if let Some(n) = n
                && !out.contains(n)
            {
                out.push(n.clone());
            }
        };
        let p = &self.planform;
        push(&p.sweep);
        push(&p.dihedral);
        push(&p.span);
        for k in &self.key_sections {
            push(&k.twist);
            push(&k.chord);
            for s in &k.shift {
                push(s);
            }
            for v in k.thickness.values() {
                push(&Some(v.clone()));
            }
            for v in k.camber.values() {
                push(&Some(v.clone()));
            }
        }
        out
    }

    /// Samples the wing at normalised (section s, span t): the surface, or with a
    /// [`second`](Self::second) face the first surface for s ≤ ½ and the second above.
    fn sample(&self, db: &GeomDb, s: f64, t: f64) -> Point3 {
        let face = SectionFace {
            surface: self.surface,
            spanwise: self.spanwise,
            reverse_section: self.reverse_section,
            reverse_span: self.reverse_span,
        };
        match &self.second {
            None => sample_face(db, &face, s, t),
            Some(_) if s <= 0.5 => sample_face(db, &face, 2.0 * s, t),
            Some(second) => sample_face(db, second, 2.0 * s - 1.0, t),
        }
    }

    fn section_samples(&self, db: &GeomDb, t: f64) -> Vec<Point3> {
        (0..self.n_s)
            .map(|i| self.sample(db, i as f64 / (self.n_s - 1) as f64, t))
            .collect()
    }

    /// Binds the spec to `db` and to the master modifier's variables `names` with their
    /// initial values `x0` (the master is the sampled surface at `x0`; deviations are
    /// x − x0). Samples the initial master and fits every key section; errors name the
    /// key section or the variable.
    pub fn bind(&self, db: &GeomDb, names: &[String], x0: &[f64]) -> Result<WingMaster> {
        for s in std::iter::once(self.surface).chain(self.second.map(|f| f.surface)) {
            if s.index() >= db.surfaces.len() {
                return Err(err(format!(
                    "{} does not exist (the model has {} surfaces)",
                    s,
                    db.surfaces.len()
                )));
            }
        }
        if self.n_s < 20 || self.n_t < 2 {
            return Err(err(format!(
                "{} × {} master: at least 20 points per section and 2 stations",
                self.n_s, self.n_t
            )));
        }
        if names.len() != x0.len() {
            return Err(err(format!(
                "{} variable names but {} initial values",
                names.len(),
                x0.len()
            )));
        }
        let f = self.reference_chord_fraction;
        if !(0.0..=1.0).contains(&f) {
            return Err(err(format!(
                "reference_chord_fraction = {f} must be in [0, 1]"
            )));
        }
        let e = unit(self.span_axis, "span_axis")?;
        let a = unit(
            self.streamwise - e * self.streamwise.dot(&e),
            "streamwise (with its span component removed)",
        )?;
        let n = a.cross(&e);
        if self.key_sections.is_empty() {
            return Err(err("no key sections"));
        }
        let mut used = vec![false; names.len()];
        let mut find = |v: &Option<String>, what: &str| -> Result<Option<usize>> {
            match v {
                None => Ok(None),
                Some(v) => {
                    let k = names.iter().position(|m| m == v).ok_or_else(|| {
                        err(format!(
                            "{what}: variable '{v}' is not one of the modifier's variables"
                        ))
                    })?;
                    used[k] = true;
                    Ok(Some(k))
                }
            }
        };
        let planform = [
            find(&self.planform.sweep, "planform sweep")?,
            find(&self.planform.dihedral, "planform dihedral")?,
            find(&self.planform.span, "planform span")?,
        ];
        // Least squares (no minimax rounds), as before the rounds existed: the key sections
        // are the surface's own exact samples, and the master only uses the fit's deviations.
        let opts = FitOptions::default()
            .with_camber_points(self.camber_points)
            .with_thickness_extra(self.thickness_extra)
            .with_minimax_rounds(0);
        let mut keys = Vec::with_capacity(self.key_sections.len());
        let mut prev_t = f64::NEG_INFINITY;
        for (k, ks) in self.key_sections.iter().enumerate() {
            let what = format!("key section {k} (t = {})", ks.t);
            if !(ks.t >= 0.0 && ks.t <= 1.0) || ks.t <= prev_t {
                return Err(err(format!("{what}: t must increase within [0, 1]")));
            }
            prev_t = ks.t;
            let samples = self.section_samples(db, ks.t);
            let frame = section_frame(&samples, e, f).map_err(|e| err(format!("{what}: {e}")))?;
            let pts2: Vec<[f64; 2]> = samples
                .iter()
                .map(|p| {
                    let d = p - frame.leading_edge;
                    [d.dot(&frame.x), d.dot(&frame.z)]
                })
                .collect();
            let airfoil = Airfoil {
                name: what.clone(),
                points: pts2.clone(),
                warnings: Vec::new(),
            };
            let na = airfoil.normalise().map_err(|e| {
                err(format!(
                    "{what}: {e} (the section parameter must run from the trailing edge round \
                     the leading edge back to the trailing edge)"
                ))
            })?;
            let fit = fit_normalised(&na, &what, &opts).map_err(|e| err(format!("{what}: {e}")))?;
            if fit.points.len() != self.n_s {
                return Err(err(format!(
                    "{what}: the fit kept {} of {} samples (repeated points?)",
                    fit.points.len(),
                    self.n_s
                )));
            }
            // The fit orders points upper surface first: find which way round they are.
            let mismatch = |rev: bool| -> f64 {
                fit.points
                    .iter()
                    .enumerate()
                    .map(|(i, q)| {
                        let g = fit.frame.to_global(*q);
                        let p = pts2[if rev { self.n_s - 1 - i } else { i }];
                        (g[0] - p[0]).powi(2) + (g[1] - p[1]).powi(2)
                    })
                    .sum()
            };
            let rev = mismatch(true) < mismatch(false);
            let order = (0..self.n_s)
                .map(|i| if rev { self.n_s - 1 - i } else { i })
                .collect();
            let modifier = SectionModifier::from_fit(&fit)?;
            let twist = find(&ks.twist, &what)?;
            let chord = find(&ks.chord, &what)?;
            let shift = [
                find(&ks.shift[0], &what)?,
                find(&ks.shift[1], &what)?,
                find(&ks.shift[2], &what)?,
            ];
            let mut thickness = Vec::new();
            for (p, v) in &ks.thickness {
                let pi = NAMES.iter().position(|m| m == p).ok_or_else(|| {
                    err(format!(
                        "{what}: '{p}' is not a thickness parameter of Eq. (39) ({})",
                        NAMES.join(", ")
                    ))
                })?;
                thickness.push((pi, find(&Some(v.clone()), &what)?.expect("named")));
            }
            let mut camber = Vec::new();
            for (&j, v) in &ks.camber {
                if j == 0 || j + 1 >= self.camber_points {
                    return Err(err(format!(
                        "{what}: camber point {j} is not interior (1 ..= {})",
                        self.camber_points.saturating_sub(2)
                    )));
                }
                camber.push((j, find(&Some(v.clone()), &what)?.expect("named")));
            }
            keys.push(BoundKey {
                frame,
                fit,
                modifier,
                order,
                twist,
                chord,
                shift,
                thickness,
                camber,
            });
        }
        if let Some(k) = used.iter().position(|u| !u) {
            return Err(err(format!(
                "variable '{}' is not used by the wing master",
                names[k]
            )));
        }
        let ys: Vec<f64> = keys.iter().map(|k| k.frame.y).collect();
        if let Some(w) = ys.windows(2).position(|w| w[1] <= w[0]) {
            return Err(err(format!(
                "key sections {w} and {} are not in increasing span coordinate ({} then {})",
                w + 1,
                ys[w],
                ys[w + 1]
            )));
        }
        let (root, tip) = (
            keys[0].frame.reference,
            keys[keys.len() - 1].frame.reference,
        );
        let span_length = tip.coords.dot(&e) - root.coords.dot(&e);
        let uses_planform = planform.iter().any(|p| p.is_some());
        if uses_planform && span_length.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(err(
                "planform variables need at least two key sections apart along the span",
            ));
        }
        let (r, tan_sweep0, tan_dihedral0) = if span_length > 0.0 {
            let d = tip - root;
            (
                d / span_length,
                d.dot(&a) / span_length,
                d.dot(&n) / span_length,
            )
        } else {
            (e, 0.0, 0.0)
        };
        let mut points = Vec::with_capacity(self.n_s * self.n_t);
        let mut stations = Vec::with_capacity(self.n_t);
        for j in 0..self.n_t {
            let t = j as f64 / (self.n_t - 1) as f64;
            let samples = self.section_samples(db, t);
            let frame = section_frame(&samples, e, f)
                .map_err(|e| err(format!("station {j} (t = {t}): {e}")))?;
            stations.push(Station {
                frame,
                weights: weights(&ys, frame.y),
                eta: frame.y - ys[0],
            });
            points.extend(samples);
        }
        Ok(WingMaster {
            names: names.to_vec(),
            x0: x0.to_vec(),
            base: MasterGrid {
                n_s: self.n_s,
                n_t: self.n_t,
                points,
            },
            e,
            a,
            n,
            r,
            span_length,
            tan_sweep0,
            tan_dihedral0,
            planform,
            keys,
            stations,
        })
    }
}

impl WingMasterSpec {
    /// [`bind`](Self::bind) with the names and initial values of the master modifier `m`'s
    /// variables.
    pub fn bind_modifier(&self, db: &GeomDb, m: &param::MasterModifier) -> Result<WingMaster> {
        let names: Vec<String> = m.variables.iter().map(|v| v.name.clone()).collect();
        let x0: Vec<f64> = m.variables.iter().map(|v| v.value).collect();
        self.bind(db, &names, &x0)
            .map_err(|e| err(format!("modifier '{}': {e}", m.name)))
    }
}

/// The master sources of a parametrisation: every master modifier whose source is
/// `External(name)` with `name` a key of `specs` gets its wing master bound
/// ([`WingMasterSpec::bind_modifier`]); pass the result to `Parametrisation::bind`. External
/// names not in `specs` are left out (param then reports them as missing). A spec used by
/// two modifiers is an error (the sources are keyed by name and each binding is specific to
/// its modifier's variables).
pub fn master_sources(
    db: &GeomDb,
    p: &param::Parametrisation,
    specs: &BTreeMap<String, WingMasterSpec>,
) -> Result<param::MasterSources> {
    let mut out = param::MasterSources::new();
    for m in &p.modifiers {
        if let param::Modifier::Master(mm) = m
            && let param::MasterSpec::External(name) = &mm.source
            && let Some(spec) = specs.get(name)
        {
            if out.contains_key(name) {
                return Err(err(format!(
                    "wing master '{name}' is used by two master modifiers; give each its own"
                )));
            }
            let wm = spec.bind_modifier(db, mm)?;
            out.insert(
                name.clone(),
                std::sync::Arc::new(wm) as std::sync::Arc<dyn MasterSource>,
            );
        }
    }
    Ok(out)
}
