//! The bound wing master evaluated: the Eq. (40) deviations of the key sections, the
//! stations' twist, chord and shift, the master grid at a design vector, and its exact
//! Jacobian ([`MasterSource`] for [`WingMaster`]).

use super::*;

/// Per key section: the Eq. (40) deviation of every sample per unit chord in the key's
/// sample frame (x̂_K, ẑ_K), indexed by sample; `None` when zero.
type KeyDeviation = Option<Vec<[f64; 2]>>;

impl WingMaster {
    /// The initial master (the sampled surface).
    pub fn initial(&self) -> &MasterGrid {
        &self.base
    }

    /// The frame of station j (t = j / (n_t − 1)).
    pub fn station_frame(&self, j: usize) -> &SectionFrame {
        &self.stations[j].frame
    }

    /// The frame of key section k (from its samples).
    pub fn key_frame(&self, k: usize) -> &SectionFrame {
        &self.keys[k].frame
    }

    /// The fit of key section k (its frame, parameters and errors).
    pub fn key_fit(&self, k: usize) -> &SectionFit {
        &self.keys[k].fit
    }

    /// The initial sweep Λ₀ and dihedral Γ₀ of the reference line (radians).
    pub fn initial_sweep_dihedral(&self) -> (f64, f64) {
        (self.tan_sweep0.atan(), self.tan_dihedral0.atan())
    }

    /// Maps local Eq. (40) deviations of the fit points (chords, fit frame) to the key's
    /// sample frame per unit chord, indexed by sample.
    fn to_key_frame(&self, k: usize, dev: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let key = &self.keys[k];
        let fr: &Frame = &key.fit.frame;
        let (s, c) = fr.angle.sin_cos();
        let scale = fr.chord / key.frame.chord;
        let mut out = vec![[0.0, 0.0]; dev.len()];
        for (i, d) in dev.iter().enumerate() {
            out[key.order[i]] = [scale * (c * d[0] - s * d[1]), scale * (s * d[0] + c * d[1])];
        }
        out
    }

    /// The thickness parameters of key k at deviations `dx`.
    fn key_thickness(&self, k: usize, dx: &[f64]) -> ThicknessParams {
        let key = &self.keys[k];
        let mut v = key.fit.params.thickness.to_vec();
        for &(pi, var) in &key.thickness {
            v[pi] += dx[var];
        }
        ThicknessParams::from_vec(&v)
    }

    fn key_deviation(&self, k: usize, dx: &[f64]) -> Result<KeyDeviation> {
        let key = &self.keys[k];
        let moved = key
            .thickness
            .iter()
            .chain(&key.camber)
            .any(|&(_, v)| dx[v] != 0.0);
        if !moved {
            return Ok(None);
        }
        let th = self.key_thickness(k, dx);
        let poly = th.polygon().map_err(|e| Error::KeySection {
            key: k,
            source: Box::new(e),
        })?;
        let dp: Vec<[f64; 2]> = poly
            .points()
            .iter()
            .zip(key.modifier.base_polygon().points())
            .map(|(p, q)| [p[0] - q[0], p[1] - q[1]])
            .collect();
        let mut dq = vec![[0.0, 0.0]; key.fit.params.camber.len()];
        for &(j, v) in &key.camber {
            dq[j][1] += dx[v];
        }
        Ok(Some(
            self.to_key_frame(k, &key.modifier.deviation(&dp, &dq)),
        ))
    }

    /// Per station: (θ, Δc, shift + planform terms).
    fn station_state(&self, j: usize, dx: &[f64]) -> (f64, f64, Vector3) {
        let st = &self.stations[j];
        let (mut theta, mut dc, mut d) = (0.0, 0.0, Vector3::zeros());
        for &(k, w) in &st.weights {
            let key = &self.keys[k];
            if let Some(v) = key.twist {
                theta += w * dx[v];
            }
            if let Some(v) = key.chord {
                dc += w * dx[v];
            }
            for (c, s) in key.shift.iter().enumerate() {
                if let Some(v) = s {
                    d[c] += w * dx[*v];
                }
            }
        }
        let [sw, dh, sp] = self.planform;
        if let Some(v) = sw
            && dx[v] != 0.0
        {
            let dt = (self.tan_sweep0.atan() + dx[v]).tan() - self.tan_sweep0;
            d += self.a * (dt * st.eta);
        }
        if let Some(v) = dh
            && dx[v] != 0.0
        {
            let dt = (self.tan_dihedral0.atan() + dx[v]).tan() - self.tan_dihedral0;
            d += self.n * (dt * st.eta);
        }
        if let Some(v) = sp
            && dx[v] != 0.0
        {
            d += self.r * (dx[v] * st.eta / self.span_length);
        }
        (theta, dc, d)
    }

    fn deviations(&self, x: &[f64]) -> Result<Vec<f64>> {
        if x.len() != self.names.len() {
            return Err(err(format!(
                "{} values for {} variables",
                x.len(),
                self.names.len()
            )));
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(err(format!(
                "variable '{}' = {} is not finite",
                self.names[i], x[i]
            )));
        }
        Ok(x.iter().zip(&self.x0).map(|(a, b)| a - b).collect())
    }
}

/// `a + d` per component, leaving components with d = 0 untouched (bit for bit).
fn add(p: Point3, d: Vector3) -> Point3 {
    let mut q = p;
    for c in 0..3 {
        if d[c] != 0.0 {
            q[c] += d[c];
        }
    }
    q
}

impl MasterSource for WingMaster {
    fn variable_names(&self) -> Vec<String> {
        self.names.clone()
    }

    fn generate(&self, x: &[f64]) -> std::result::Result<MasterGrid, param::MasterError> {
        let dx = self.deviations(x)?;
        let devs: Vec<KeyDeviation> = (0..self.keys.len())
            .map(|k| self.key_deviation(k, &dx))
            .collect::<Result<_>>()?;
        let n_s = self.base.n_s;
        let mut points = self.base.points.clone();
        for (j, st) in self.stations.iter().enumerate() {
            let (theta, dc, shift) = self.station_state(j, &dx);
            let fr = &st.frame;
            let scale = 1.0 + dc / fr.chord;
            for i in 0..n_s {
                let p = self.base.points[j * n_s + i];
                let mut dsec = Vector3::zeros();
                for &(k, w) in &st.weights {
                    if let Some(d) = &devs[k] {
                        dsec += (fr.x * d[i][0] + fr.z * d[i][1]) * (w * fr.chord);
                    }
                }
                let mut disp = dsec + shift;
                if theta != 0.0 || dc != 0.0 {
                    let v = p - fr.reference + dsec;
                    disp += rotate(v, self.e, theta).0 * scale - v;
                }
                points[j * n_s + i] = add(p, disp);
            }
        }
        Ok(MasterGrid {
            n_s,
            n_t: self.base.n_t,
            points,
        })
    }

    fn jacobian(
        &self,
        x: &[f64],
    ) -> Option<std::result::Result<Vec<Vec<Vector3>>, param::MasterError>> {
        Some(self.exact_jacobian(x).map_err(Into::into))
    }
}

impl WingMaster {
    /// d(master point)/dx, exact: twist, chord, shift and planform terms by differentiation
    /// of the formula in the module doc; thickness through the analytic polygon Jacobian of
    /// conditions 1–6 and the linear Eq. (40); camber (linear) directly.
    fn exact_jacobian(&self, x: &[f64]) -> Result<Vec<Vec<Vector3>>> {
        let dx = self.deviations(x)?;
        let nv = x.len();
        let devs: Vec<KeyDeviation> = (0..self.keys.len())
            .map(|k| self.key_deviation(k, &dx))
            .collect::<Result<_>>()?;
        // Per key: (variable, d(deviation)/d(variable) per sample, key frame per unit chord).
        let mut ddev: Vec<Vec<(usize, Vec<[f64; 2]>)>> = Vec::with_capacity(self.keys.len());
        for (k, key) in self.keys.iter().enumerate() {
            let mut cols = Vec::new();
            if !key.thickness.is_empty() {
                let th = self.key_thickness(k, &dx);
                let (_, jac) = th
                    .polygon_with_jacobian(true)
                    .map_err(|e| Error::KeySection {
                        key: k,
                        source: Box::new(e),
                    })?;
                let dq0 = vec![[0.0, 0.0]; key.fit.params.camber.len()];
                for &(pi, v) in &key.thickness {
                    let dp: Vec<[f64; 2]> = jac.iter().map(|row| row[pi]).collect();
                    let d = key.modifier.deviation(&dp, &dq0);
                    cols.push((v, self.to_key_frame(k, &d)));
                }
            }
            let np = key.modifier.base_polygon().points().len();
            for &(j, v) in &key.camber {
                let mut dq = vec![[0.0, 0.0]; key.fit.params.camber.len()];
                dq[j][1] = 1.0;
                let d = key.modifier.deviation(&vec![[0.0, 0.0]; np], &dq);
                cols.push((v, self.to_key_frame(k, &d)));
            }
            ddev.push(cols);
        }
        let n_s = self.base.n_s;
        let mut out = vec![vec![Vector3::zeros(); nv]; self.base.points.len()];
        for (j, st) in self.stations.iter().enumerate() {
            let (theta, dc, _) = self.station_state(j, &dx);
            let fr = &st.frame;
            let scale = 1.0 + dc / fr.chord;
            // planform columns (the same for every point of the station)
            let mut pcol: Vec<(usize, Vector3)> = Vec::new();
            let [sw, dh, sp] = self.planform;
            if let Some(v) = sw {
                let c = (self.tan_sweep0.atan() + dx[v]).cos();
                pcol.push((v, self.a * (st.eta / (c * c))));
            }
            if let Some(v) = dh {
                let c = (self.tan_dihedral0.atan() + dx[v]).cos();
                pcol.push((v, self.n * (st.eta / (c * c))));
            }
            if let Some(v) = sp {
                pcol.push((v, self.r * (st.eta / self.span_length)));
            }
            for i in 0..n_s {
                let row = &mut out[j * n_s + i];
                let p = self.base.points[j * n_s + i];
                let mut dsec = Vector3::zeros();
                for &(k, w) in &st.weights {
                    if let Some(d) = &devs[k] {
                        dsec += (fr.x * d[i][0] + fr.z * d[i][1]) * (w * fr.chord);
                    }
                }
                let v = p - fr.reference + dsec;
                let (rv, drv) = rotate(v, self.e, theta);
                for &(k, w) in &st.weights {
                    let key = &self.keys[k];
                    if let Some(l) = key.twist {
                        row[l] += drv * (scale * w);
                    }
                    if let Some(l) = key.chord {
                        row[l] += rv * (w / fr.chord);
                    }
                    for (c, s) in key.shift.iter().enumerate() {
                        if let Some(l) = s {
                            row[*l][c] += w;
                        }
                    }
                    for (l, col) in &ddev[k] {
                        let dd = (fr.x * col[i][0] + fr.z * col[i][1]) * (w * fr.chord);
                        row[*l] += rotate(dd, self.e, theta).0 * scale;
                    }
                }
                for (l, c) in &pcol {
                    row[*l] += c;
                }
            }
        }
        Ok(out)
    }
}
