//! Reads a grid and reports the time taken and the process's peak resident memory
//! (`VmHWM` from /proc/self/status) per node.
//!
//! ```text
//! cargo run --release -p mesh --example read_mem -- --generate 99 /tmp/box.su2
//! cargo run --release -p mesh --example read_mem -- /tmp/box.su2
//! ```
//! `--generate N FILE [--binary]` writes a tetrahedral box of N³ cubes ((N+1)³ nodes) in the
//! format given by FILE's extension (`--binary`: binary MSH), in its own process, so that
//! reading is measured alone.

use std::io::BufWriter;
use std::path::Path;
use std::time::Instant;

fn vm_hwm_kib() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--generate") {
        let n: usize = args.get(1).ok_or("--generate N FILE")?.parse()?;
        let path = Path::new(args.get(2).ok_or("--generate N FILE")?);
        let mut format = mesh::io::Format::from_path(path).ok_or("unknown extension")?;
        if args.get(3).map(String::as_str) == Some("--binary") {
            format = mesh::io::Format::Msh(mesh::msh::Encoding::Binary);
        }
        let m = mesh::generate::box_tets(n, n, n, [0.0; 3], [1.0; 3]);
        let mut w = BufWriter::new(std::fs::File::create(path)?);
        mesh::io::write(&m, format, &mut w)?;
        println!(
            "wrote {} nodes, {} tets to {}",
            m.n_nodes(),
            m.tets().len(),
            path.display()
        );
        return Ok(());
    }
    let path = Path::new(
        args.first()
            .ok_or("usage: read_mem FILE | --generate N FILE")?,
    );
    let before = vm_hwm_kib().unwrap_or(0);
    let t = Instant::now();
    let m = mesh::io::read_path(path)?;
    let secs = t.elapsed().as_secs_f64();
    let hwm = vm_hwm_kib().unwrap_or(0);
    let n = m.n_nodes().max(1) as f64;
    println!(
        "{}: {} nodes, {} cells, {} markers read in {secs:.3} s ({:.2} M nodes/s); \
         peak RSS {:.1} MiB (before reading {:.1} MiB): {:.0} bytes/node",
        path.display(),
        m.n_nodes(),
        m.cells.len(),
        m.markers.len(),
        n / secs / 1e6,
        hwm as f64 / 1024.0,
        before as f64 / 1024.0,
        hwm as f64 * 1024.0 / n
    );
    Ok(())
}
