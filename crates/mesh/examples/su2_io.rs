//! Times the three grid steps of a deformation run that live in this crate — SU2 read,
//! node adjacency, SU2 write — on one file, and prints a fingerprint of each result so two
//! builds can be checked to give the same grid, adjacency and bytes.
//!
//! ```text
//! cargo run --release -p mesh --example su2_io -- IN.su2 [OUT.su2]
//! ```
//! Per step: wall seconds and process CPU seconds (user + system, from /proc/self/stat, in
//! clock ticks of 10 ms); at the end the peak resident memory (VmHWM). Without `OUT.su2` the
//! output goes to a sink (formatting only). The fingerprints are `DefaultHasher` (SipHash with
//! fixed keys) values of the coordinate bits, the connectivity, the markers, the adjacency
//! rows and the written bytes. `SU2_IO_STEPS=read` (or `adjacency`) stops after that step.

use std::hash::{DefaultHasher, Hash, Hasher};
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// Process CPU seconds (user + system) from /proc/self/stat.
fn cpu_seconds() -> f64 {
    let Ok(s) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // Fields after the command name (which is in parentheses and may hold spaces).
    let rest = &s[s.rfind(')').map_or(0, |i| i + 1)..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| {
        f.get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    // utime and stime are fields 14 and 15 of the full line, 12 and 13 after the name.
    (ticks(11) + ticks(12)) / 100.0
}

fn vm_hwm_kib() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// A writer that hashes what it is given.
struct HashWriter(DefaultHasher, u64);

impl Write for HashWriter {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.write(b);
        self.1 += b.len() as u64;
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

fn timed<T>(label: &str, f: impl FnOnce() -> T) -> T {
    let (c, t) = (cpu_seconds(), Instant::now());
    let r = f();
    println!(
        "{label}: {:.3} s wall, {:.2} s cpu",
        t.elapsed().as_secs_f64(),
        cpu_seconds() - c
    );
    r
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let input = Path::new(args.first().ok_or("usage: su2_io IN.su2 [OUT.su2]")?);
    // SU2_IO_STEPS=read|adjacency|write: stop after that step (for instruction counts of
    // a step under `valgrind --tool=cachegrind`, by differences).
    let steps = std::env::var("SU2_IO_STEPS").unwrap_or_default();
    let m = timed("read", || mesh::io::read_path(input))?;
    if steps == "read" {
        return Ok(());
    }
    let adj = timed("adjacency", || mesh::Adjacency::build(&m));
    if steps == "adjacency" {
        return Ok(());
    }
    let mut w = HashWriter(DefaultHasher::new(), 0);
    match args.get(1) {
        Some(out) => timed("write", || -> std::io::Result<()> {
            let mut f = std::io::BufWriter::new(std::fs::File::create(out)?);
            mesh::su2::write(&m, &mut f)?;
            f.flush()
        })?,
        None => timed("write (sink)", || mesh::su2::write(&m, &mut w))?,
    }
    let mut h = DefaultHasher::new();
    m.dim.hash(&mut h);
    for p in &m.coords {
        p.map(f64::to_bits).hash(&mut h);
    }
    m.cells.hash_into(&mut h);
    for mk in &m.markers {
        mk.name.hash(&mut h);
        mk.elements.hash_into(&mut h);
    }
    m.su2_extra.hash(&mut h);
    let mut ha = DefaultHasher::new();
    adj.offsets.hash(&mut ha);
    adj.indices.hash(&mut ha);
    println!(
        "{} nodes, {} cells, {} edges; fingerprints mesh {:016x} adjacency {:016x}{}",
        m.n_nodes(),
        m.cells.len(),
        adj.n_edges(),
        h.finish(),
        ha.finish(),
        if args.get(1).is_none() {
            format!(" written {:016x} ({} bytes)", w.0.finish(), w.1)
        } else {
            String::new()
        }
    );
    println!("peak RSS {} kB", vm_hwm_kib().unwrap_or(0));
    Ok(())
}

/// Hashing of an element set through its public iteration.
trait HashInto {
    fn hash_into(&self, h: &mut DefaultHasher);
}

impl HashInto for mesh::Elements {
    fn hash_into(&self, h: &mut DefaultHasher) {
        for g in self.groups() {
            g.kind.vtk_code().hash(h);
            g.nodes.hash(h);
            g.entity.hash(h);
        }
    }
}
