//! Node adjacency against a brute-force edge set.

use std::collections::BTreeSet;

use mesh::{Adjacency, generate};

fn brute_force(m: &mesh::Mesh) -> BTreeSet<[u32; 2]> {
    let mut s = BTreeSet::new();
    for (kind, nodes) in m.cells.iter() {
        for e in kind.edges() {
            let (a, b) = (nodes[e[0] as usize], nodes[e[1] as usize]);
            s.insert([a.min(b), a.max(b)]);
        }
    }
    s
}

#[test]
fn adjacency_matches_brute_force_on_shuffled_box() {
    let mut m = generate::box_tets(4, 3, 5, [0.0; 3], [1.0; 3]);
    generate::shuffle_nodes(&mut m, 7);
    let a = Adjacency::build(&m);
    let edges: BTreeSet<[u32; 2]> = a.edges().into_iter().collect();
    assert_eq!(edges, brute_force(&m));
    for i in 0..a.n_nodes() {
        let row = a.neighbours(i);
        assert!(
            row.windows(2).all(|w| w[0] < w[1]),
            "row {i} sorted and unique"
        );
        assert!(!row.contains(&(i as u32)));
    }
}

#[test]
fn adjacency_is_independent_of_thread_count() {
    let m = generate::box_tets(6, 5, 4, [0.0; 3], [1.0; 3]);
    let a1 = testkit::with_threads(1, || Adjacency::build(&m));
    let a4 = testkit::with_threads(4, || Adjacency::build(&m));
    assert_eq!(a1, a4);
}

#[test]
fn real_brick_edge_count_satisfies_euler() {
    // For a tetrahedral grid of a ball: V - E + F - T = 1.
    let m = crate::common::read_su2(&crate::common::shared_su2("mesh_brick_tets_ffd.su2"));
    let a = Adjacency::build(&m);
    let mut faces = BTreeSet::new();
    for t in m.tets() {
        for f in [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
            let mut k = [t[f[0]], t[f[1]], t[f[2]]];
            k.sort_unstable();
            faces.insert(k);
        }
    }
    let chi = m.n_nodes() as i64 - a.n_edges() as i64 + faces.len() as i64 - m.tets().len() as i64;
    assert_eq!(chi, 1);
}
