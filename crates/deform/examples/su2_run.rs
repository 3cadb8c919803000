//! End-to-end run of the benchmark case on a file, as `aeroshape deform` does it: read an SU2
//! grid, pitch the `wing` marker by −5° about the spanwise axis through (1.75, 0, 2), slide
//! `y_m`, fix the rest, write the result as SU2; prints seconds per phase
//! (read, deformation and its phases, write). Usage:
//! `su2_run IN.su2 OUT.su2` (`STIFF=l2|wall`, default wall). Make the grid with
//! `N=126 WRITE_SU2=IN.su2 quality_probe`.

use std::time::Instant;

use deform::{DeformOptions, Stiffness, deform};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (input, output) = (&args[1], &args[2]);
    let t = Instant::now();
    let m = mesh::io::read_path(input.as_ref()).unwrap();
    let read = t.elapsed().as_secs_f64();
    let bc = deform::generate::wing_pitch_conditions();
    let stiffness = match std::env::var("STIFF").as_deref() {
        Ok("l2") => Stiffness::InverseLengthSquared,
        _ => Stiffness::WallDistance,
    };
    let t = Instant::now();
    let d = deform(
        &m,
        &bc,
        &DeformOptions {
            stiffness,
            ..Default::default()
        },
    )
    .unwrap();
    let run = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let mut out = m;
    out.coords = d.coords;
    let mut f = std::io::BufWriter::new(std::fs::File::create(output).unwrap());
    mesh::io::write(&out, mesh::io::Format::Su2, &mut f).unwrap();
    drop(f);
    let write = t.elapsed().as_secs_f64();
    let r = &d.report;
    println!(
        "{} nodes: read {read:.2} s, deform {run:.2} s (it {} + {} R), write {write:.2} s; q min {:.4} -> {:.4} ({:.1} %), inverted {}",
        r.nodes,
        r.iterations,
        r.rotation_iterations,
        r.quality_before.min,
        r.quality_after.min,
        100.0 * r.quality_after.min / r.quality_before.min,
        r.quality_after.n_nonpositive
    );
    let s = &r.seconds;
    println!(
        "seconds: setup {:.2} / assemble {:.2} / precond {:.2} / rotation {:.2} / solve {:.2} / quality {:.2}",
        s.setup, s.assemble, s.precond, s.rotation, s.solve, s.quality
    );
}
