//! The wall of a volume grid split by surface component by geometry alone
//! (`surfgrid::classify::wall_surface`), checked against what the grid's writer knew: the
//! default case's `grid.msh` is aeroshape's own, whose element entity tags are the surface
//! component + 1. The same grid as SU2 with other marker names gives the same split.

use geom_db::GeomDb;
use mesh::Mesh;
use surfgrid::classify::wall_surface;

fn default_case() -> (GeomDb, Mesh) {
    let dir = format!(
        "{}/../../fixtures/cases/default",
        env!("CARGO_MANIFEST_DIR")
    );
    let path = format!("{dir}/wing_body.ron");
    let db = GeomDb::from_ron_str(&std::fs::read_to_string(&path).unwrap(), &path).unwrap();
    let grid = mesh::io::read_path(format!("{dir}/grid.msh").as_ref()).unwrap();
    (db, grid)
}

/// Per surface component, the sorted wall triangles of a split surface mesh.
fn split_of(db: &GeomDb, s: &Mesh) -> Vec<Vec<[u32; 3]>> {
    (0..db.surface_components.len())
        .map(|k| {
            let name = surfgrid::grid::marker_name(db, geom_db::SurfCompId::from_index(k));
            let mut t: Vec<[u32; 3]> = s
                .marker(&name)
                .into_iter()
                .flat_map(|m| m.elements.group(mesh::ElementKind::Triangle))
                .flat_map(|g| g.iter().map(|t| [t[0], t[1], t[2]]).collect::<Vec<_>>())
                .collect();
            t.sort_unstable();
            t
        })
        .collect()
}

#[test]
fn split_by_geometry_matches_the_writers_entity_tags() {
    let (db, grid) = default_case();
    let wall = ["wing".to_string(), "fuselage".to_string()];
    // what the writer knew: entity tag − 1 = component
    let mut tagged: Vec<Vec<[u32; 3]>> = vec![Vec::new(); db.surface_components.len()];
    for name in &wall {
        for g in grid.marker(name).unwrap().elements.groups() {
            for (e, t) in g.iter().enumerate() {
                tagged[(g.entity[e] - 1) as usize].push([t[0], t[1], t[2]]);
            }
        }
    }
    for t in &mut tagged {
        t.sort_unstable();
    }
    assert!(
        tagged.iter().all(|t| !t.is_empty()),
        "every component has triangles"
    );
    let by_geometry = split_of(
        &db,
        &wall_surface(&db, &grid, &wall, &Default::default()).unwrap(),
    );
    assert_eq!(by_geometry, tagged);

    // the same grid as SU2 (no tags, no parameters) with markers a mesher might name
    let mut renamed = grid.clone();
    for m in &mut renamed.markers {
        m.name = format!("BC_{}", m.name.to_uppercase());
    }
    let mut buf = Vec::new();
    mesh::su2::write(&renamed, &mut buf).unwrap();
    let su2 = mesh::su2::read(&buf[..], "renamed.su2".as_ref()).unwrap();
    let wall2 = ["BC_WING".to_string(), "BC_FUSELAGE".to_string()];
    let s = wall_surface(&db, &su2, &wall2, &Default::default()).unwrap();
    assert_eq!(split_of(&db, &s), tagged);
}

/// A wall marker that is not on the geometry at all (the far-field box) is refused with the
/// node and the distance named, not a panic.
#[test]
fn a_far_field_named_as_wall_is_refused_by_distance() {
    let (db, grid) = default_case();
    let e = surfgrid::classify_wall(
        &db,
        &grid,
        &["farfield".to_string()],
        &surfgrid::ClassifyOptions::default(),
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(msg.starts_with("node "), "{msg}");
    assert!(msg.contains("exceeds the tolerance"), "{msg}");
}
