//! Quality of the wing-in-box case (the benchmark's generator) pitched 5°, for option
//! variants given in the environment: `N` (cubes per side, default 30), `STIFF` (l, l2,
//! volume, wall), `ROT` (0/1), `RATIO` (guard's min_quality_ratio, to force increments).
//! `WRITE_SU2=path` writes the case's grid as SU2 instead (nodes randomly renumbered with
//! `SHUFFLE=seed`).

use deform::{DeformOptions, Stiffness, deform};

fn main() {
    let env = |k: &str, d: &str| std::env::var(k).unwrap_or_else(|_| d.into());
    let n: usize = env("N", "30").parse().unwrap();
    let mut m = deform::generate::wing_in_box(n);
    let bc = deform::generate::wing_pitch_conditions();
    if let Ok(path) = std::env::var("WRITE_SU2") {
        // Write the case's grid (for end-to-end runs of `aeroshape deform`) and stop.
        if let Ok(seed) = std::env::var("SHUFFLE") {
            mesh::generate::shuffle_nodes(&mut m, seed.parse().unwrap());
        }
        let mut f = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        mesh::io::write(&m, mesh::io::Format::Su2, &mut f).unwrap();
        println!("wrote {path}: {} nodes", m.n_nodes());
        return;
    }
    let stiffness = match env("STIFF", "l2").as_str() {
        "l" => Stiffness::InverseLength,
        "volume" => Stiffness::Volume,
        "wall" => Stiffness::WallDistance,
        _ => Stiffness::InverseLengthSquared,
    };
    let opts = DeformOptions {
        stiffness,
        adapt_rotation: env("ROT", "1") == "1",
        min_quality_ratio: env("RATIO", "0.2").parse().unwrap(),
        ..Default::default()
    };
    let t = std::time::Instant::now();
    let d = deform(&m, &bc, &opts).unwrap();
    let r = &d.report;
    let q = deform::cell_quality(&m, &d.coords);
    let mut worst: Vec<usize> = (0..q.len()).collect();
    worst.sort_by(|&a, &b| q[a].total_cmp(&q[b]));
    let tets = m.tets();
    let cen = |c: usize| {
        let mut s = [0.0; 3];
        for &v in &tets[c] {
            for k in 0..3 {
                s[k] += 0.25 * m.coords[v as usize][k];
            }
        }
        s
    };
    println!(
        "nodes {} q min {:.4} -> {:.4} ({:.2} %), p1 {:.4} -> {:.4}, inverted {}, increments {}, it {}, {:.2} s",
        m.n_nodes(),
        r.quality_before.min,
        r.quality_after.min,
        100.0 * r.quality_after.min / r.quality_before.min,
        r.quality_before.p1,
        r.quality_after.p1,
        r.quality_after.n_nonpositive,
        r.increments,
        r.iterations,
        t.elapsed().as_secs_f64()
    );
    for &c in worst.iter().take(5) {
        let p = cen(c);
        println!(
            "  cell {c}: q {:.4}, centroid ({:.3}, {:.3}, {:.3})",
            q[c], p[0], p[1], p[2]
        );
    }
}
