//! Criterion benchmarks of the mesh crate on a generated tetrahedral box of about one
//! million nodes (`MESH_BENCH_N` cubes per side, default 99 → 10^6 nodes, 5.8 M tets):
//! SU2 and MSH read/write throughput in nodes per second, adjacency build, quality.

use std::fs::File;
use std::hint::black_box;
use std::io::{BufReader, BufWriter};
use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mesh::msh::Encoding;

fn size() -> usize {
    std::env::var("MESH_BENCH_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(99)
}

fn write_file(m: &mesh::Mesh, path: &Path, f: mesh::io::Format) {
    let mut w = BufWriter::new(File::create(path).unwrap());
    mesh::io::write(m, f, &mut w).unwrap();
}

fn benches(c: &mut Criterion) {
    let n = size();
    let m = mesh::generate::box_tets(n, n, n, [0.0; 3], [1.0; 3]);
    let nodes = m.n_nodes() as u64;
    let dir = tempfile::tempdir().unwrap();
    let su2 = dir.path().join("box.su2");
    let msh_a = dir.path().join("box_ascii.msh");
    let msh_b = dir.path().join("box_binary.msh");
    write_file(&m, &su2, mesh::io::Format::Su2);
    write_file(&m, &msh_a, mesh::io::Format::Msh(Encoding::Ascii));
    write_file(&m, &msh_b, mesh::io::Format::Msh(Encoding::Binary));

    let mut g = c.benchmark_group("mesh");
    g.sample_size(10);
    g.throughput(Throughput::Elements(nodes));
    g.bench_function("su2_read", |b| {
        b.iter(|| {
            let r = BufReader::with_capacity(1 << 18, File::open(&su2).unwrap());
            black_box(mesh::su2::read(r, &su2).unwrap())
        })
    });
    g.bench_function("su2_write", |b| {
        b.iter(|| mesh::su2::write(&m, &mut std::io::sink()).unwrap())
    });
    g.bench_function("msh_read_ascii", |b| {
        b.iter(|| {
            let r = BufReader::with_capacity(1 << 18, File::open(&msh_a).unwrap());
            black_box(mesh::msh::read(r, &msh_a).unwrap())
        })
    });
    g.bench_function("msh_read_binary", |b| {
        b.iter(|| {
            let r = BufReader::with_capacity(1 << 18, File::open(&msh_b).unwrap());
            black_box(mesh::msh::read(r, &msh_b).unwrap())
        })
    });
    g.bench_function("msh_write_ascii", |b| {
        b.iter(|| mesh::msh::write(&m, Encoding::Ascii, &mut std::io::sink()).unwrap())
    });
    g.bench_function("msh_write_binary", |b| {
        b.iter(|| mesh::msh::write(&m, Encoding::Binary, &mut std::io::sink()).unwrap())
    });
    g.bench_function("adjacency_build", |b| {
        b.iter(|| black_box(mesh::Adjacency::build(&m)))
    });
    g.bench_function("cell_quality", |b| {
        b.iter(|| black_box(mesh::quality::cell_quality(&m)))
    });
    g.finish();
}

criterion_group!(mesh_benches, benches);
criterion_main!(mesh_benches);
