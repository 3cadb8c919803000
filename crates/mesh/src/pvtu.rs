//! The index of a grid written in pieces (`.pvtu`, VTK's parallel unstructured grid): one
//! `.vtu` per piece, each written by [`crate::vtu::write`], and this file naming them, for
//! ParaView to open as one grid.

use std::io::Write;

/// Writes the `.pvtu` index of pieces written by [`crate::vtu::write`] (`sources`: the
/// pieces' paths relative to the index's directory, written with `/`), whose point data
/// hold the displacement when `displacement` is true. The arrays declared are those the
/// pieces hold: point data `displacement` (if any) and `quality`, cell data `quality` and
/// `marker`.
///
/// ```
/// let mut buf = Vec::new();
/// mesh::pvtu::write(&["out/out_0.vtu".into(), "out/out_1.vtu".into()], true, &mut buf).unwrap();
/// let text = String::from_utf8(buf).unwrap();
/// assert!(text.contains("<Piece Source=\"out/out_1.vtu\"/>"));
/// assert!(text.contains("Name=\"displacement\""));
/// ```
pub fn write<W: Write + ?Sized>(
    sources: &[String],
    displacement: bool,
    w: &mut W,
) -> std::io::Result<()> {
    let mut x = String::new();
    x.push_str("<?xml version=\"1.0\"?>\n");
    x.push_str("<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
    x.push_str("  <PUnstructuredGrid GhostLevel=\"0\">\n");
    x.push_str("    <PPointData Scalars=\"quality\">\n");
    if displacement {
        x.push_str(
            "      <PDataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\"/>\n",
        );
    }
    x.push_str("      <PDataArray type=\"Float64\" Name=\"quality\" NumberOfComponents=\"1\"/>\n");
    x.push_str("    </PPointData>\n    <PCellData Scalars=\"quality\">\n");
    x.push_str("      <PDataArray type=\"Float64\" Name=\"quality\" NumberOfComponents=\"1\"/>\n");
    x.push_str("      <PDataArray type=\"Int32\" Name=\"marker\" NumberOfComponents=\"1\"/>\n");
    x.push_str("    </PCellData>\n    <PPoints>\n");
    x.push_str("      <PDataArray type=\"Float64\" NumberOfComponents=\"3\"/>\n");
    x.push_str("    </PPoints>\n");
    for s in sources {
        x.push_str(&format!("    <Piece Source=\"{}\"/>\n", escape(s)));
    }
    x.push_str("  </PUnstructuredGrid>\n</VTKFile>\n");
    w.write_all(x.as_bytes())
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    #[test]
    fn declares_the_arrays_the_pieces_hold() {
        // A piece as vtu::write makes it, and the index's declarations of the same arrays.
        let m = crate::generate::box_tets(1, 1, 1, [0.0; 3], [1.0; 3]);
        let d = vec![[0.0; 3]; m.n_nodes()];
        let mut piece = Vec::new();
        let opts = crate::vtu::VtuOptions::default().with_displacement(&d);
        crate::vtu::write(&m, &opts, &mut piece).unwrap();
        let piece = String::from_utf8_lossy(&piece).into_owned();
        let mut index = Vec::new();
        super::write(&["p/p_0.vtu".into()], true, &mut index).unwrap();
        let index = String::from_utf8(index).unwrap();
        for (ty, name, n) in [
            ("Float64", "displacement", 3),
            ("Float64", "quality", 1),
            ("Int32", "marker", 1),
        ] {
            let tag = format!("type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{n}\"");
            assert!(piece.contains(&tag), "piece lacks {tag}");
            assert!(index.contains(&tag), "index lacks {tag}");
        }
        assert!(
            piece.contains("header_type=\"UInt64\"") && index.contains("header_type=\"UInt64\"")
        );
        let mut without = Vec::new();
        super::write(&["p/p_0.vtu".into()], false, &mut without).unwrap();
        assert!(!String::from_utf8(without).unwrap().contains("displacement"));
    }
}
