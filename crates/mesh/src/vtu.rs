//! VTK XML unstructured grid (`.vtu`) for ParaView: writer (raw appended binary or inline
//! base64) with point data `displacement` and `quality` and cell data `quality` and
//! `marker`, and a reader for the same subset (ASCII, inline base64 and appended raw or
//! base64 arrays, uncompressed or zlib-compressed as ParaView writes by default).
//!
//! Cells: the grid's cells first (in canonical order, `marker` = 0), then the boundary
//! elements of each marker (`marker` = index + 1). Marker names travel as field data arrays
//! `marker:NAME` holding the marker number.

use std::io::{Read, Write};
use std::path::Path;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as B64;

use crate::error::{Error, Location, Result};
use crate::grid::{ElementKind, Elements, Marker, Mesh};
use crate::quality;

/// How array data are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VtuEncoding {
    /// Raw little-endian bytes in an `<AppendedData encoding="raw">` block (smallest,
    /// fastest; ParaView's default).
    #[default]
    AppendedRaw,
    /// Base64 inside each `<DataArray format="binary">` (pure text file).
    Base64,
}

/// What to write besides the grid.
#[derive(Debug, Clone, Copy, Default)]
pub struct VtuOptions<'a> {
    /// Array encoding.
    pub encoding: VtuEncoding,
    /// Optional per-node displacement (point data `displacement`).
    pub displacement: Option<&'a [[f64; 3]]>,
}

impl<'a> VtuOptions<'a> {
    /// Sets the displacement field.
    pub fn with_displacement(mut self, d: &'a [[f64; 3]]) -> Self {
        self.displacement = Some(d);
        self
    }
    /// Sets the encoding.
    pub fn with_encoding(mut self, e: VtuEncoding) -> Self {
        self.encoding = e;
        self
    }
}

struct Array {
    name: String,
    ty: &'static str,
    ncomp: usize,
    bytes: Vec<u8>,
}

fn le_f64(v: impl Iterator<Item = f64>) -> Vec<u8> {
    v.flat_map(f64::to_le_bytes).collect()
}
fn le_i64(v: impl Iterator<Item = i64>) -> Vec<u8> {
    v.flat_map(i64::to_le_bytes).collect()
}
fn le_i32(v: impl Iterator<Item = i32>) -> Vec<u8> {
    v.flat_map(i32::to_le_bytes).collect()
}

/// Writes one `<DataArray>` tag; appended arrays are queued in `list`.
fn array_tag<'a>(
    x: &mut String,
    a: &'a Array,
    enc: VtuEncoding,
    offset: &mut u64,
    list: &mut Vec<&'a Array>,
) {
    x.push_str(&format!(
        "        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\"",
        a.ty,
        xml_escape(&a.name),
        a.ncomp
    ));
    match enc {
        VtuEncoding::AppendedRaw => {
            x.push_str(&format!(" format=\"appended\" offset=\"{offset}\"/>\n"));
            *offset += 8 + a.bytes.len() as u64;
            list.push(a);
        }
        VtuEncoding::Base64 => {
            let mut block = (a.bytes.len() as u64).to_le_bytes().to_vec();
            block.extend_from_slice(&a.bytes);
            x.push_str(&format!(
                " format=\"binary\">{}</DataArray>\n",
                B64.encode(&block)
            ));
        }
    }
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Writes `mesh` as a VTK XML unstructured grid. The displacement, if given, must have one
/// entry per node.
///
/// ```
/// let m = mesh::generate::box_tets(1, 1, 1, [0.0; 3], [1.0; 3]);
/// let mut buf = Vec::new();
/// mesh::vtu::write(&m, &mesh::vtu::VtuOptions::default(), &mut buf).unwrap();
/// let back = mesh::vtu::read(&buf[..], "box.vtu".as_ref()).unwrap();
/// assert_eq!(back.tets(), m.tets());
/// assert_eq!(back.markers.len(), 6);
/// ```
pub fn write<W: Write + ?Sized>(
    mesh: &Mesh,
    opts: &VtuOptions<'_>,
    w: &mut W,
) -> std::io::Result<()> {
    if let Some(d) = opts.displacement
        && d.len() != mesh.n_nodes()
    {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "displacement has {} entries for {} nodes",
                d.len(),
                mesh.n_nodes()
            ),
        ));
    }
    let n = mesh.n_nodes();
    let cq = quality::cell_quality(mesh);
    let nq = quality::node_quality(mesh, &cq);
    // Cells: grid cells then marker elements.
    let mut sets: Vec<(&Elements, i32)> = vec![(&mesh.cells, 0)];
    for (i, m) in mesh.markers.iter().enumerate() {
        sets.push((&m.elements, i as i32 + 1));
    }
    let n_cells: usize = sets.iter().map(|(s, _)| s.len()).sum();
    let mut conn = Vec::new();
    let mut offs = Vec::with_capacity(n_cells);
    let mut types = Vec::with_capacity(n_cells);
    let mut marker = Vec::with_capacity(n_cells);
    let mut cell_q = Vec::with_capacity(n_cells);
    let mut end = 0i64;
    for (set, id) in &sets {
        for (kind, nodes) in set.iter() {
            conn.extend(nodes.iter().map(|&v| i64::from(v)));
            end += nodes.len() as i64;
            offs.push(end);
            types.push(kind.vtk_code());
            marker.push(*id);
        }
    }
    cell_q.extend_from_slice(&cq);
    cell_q.resize(n_cells, f64::NAN);
    let mut point_arrays = Vec::new();
    if let Some(d) = opts.displacement {
        point_arrays.push(Array {
            name: "displacement".into(),
            ty: "Float64",
            ncomp: 3,
            bytes: le_f64(d.iter().flat_map(|p| p.iter().copied())),
        });
    }
    point_arrays.push(Array {
        name: "quality".into(),
        ty: "Float64",
        ncomp: 1,
        bytes: le_f64(nq.iter().copied()),
    });
    let cell_arrays = vec![
        Array {
            name: "quality".into(),
            ty: "Float64",
            ncomp: 1,
            bytes: le_f64(cell_q.iter().copied()),
        },
        Array {
            name: "marker".into(),
            ty: "Int32",
            ncomp: 1,
            bytes: le_i32(marker.iter().copied()),
        },
    ];
    let points = Array {
        name: "Points".into(),
        ty: "Float64",
        ncomp: 3,
        bytes: le_f64(mesh.coords.iter().flat_map(|p| p.iter().copied())),
    };
    let cells = [
        Array {
            name: "connectivity".into(),
            ty: "Int64",
            ncomp: 1,
            bytes: le_i64(conn.into_iter()),
        },
        Array {
            name: "offsets".into(),
            ty: "Int64",
            ncomp: 1,
            bytes: le_i64(offs.into_iter()),
        },
        Array {
            name: "types".into(),
            ty: "UInt8",
            ncomp: 1,
            bytes: types,
        },
    ];
    let mut offset = 0u64;
    let mut x = String::new();
    let enc = opts.encoding;
    let mut appended: Vec<&Array> = Vec::new();
    x.push_str("<?xml version=\"1.0\"?>\n");
    x.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
    x.push_str("  <UnstructuredGrid>\n");
    if !mesh.markers.is_empty() {
        x.push_str("    <FieldData>\n");
        for (i, m) in mesh.markers.iter().enumerate() {
            x.push_str(&format!(
                "      <DataArray type=\"Int32\" Name=\"marker:{}\" NumberOfTuples=\"1\" format=\"ascii\">{}</DataArray>\n",
                xml_escape(&m.name),
                i + 1
            ));
        }
        x.push_str("    </FieldData>\n");
    }
    x.push_str(&format!(
        "    <Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n_cells}\">\n"
    ));
    x.push_str("      <PointData Scalars=\"quality\">\n");
    for a in &point_arrays {
        array_tag(&mut x, a, enc, &mut offset, &mut appended);
    }
    x.push_str("      </PointData>\n      <CellData Scalars=\"quality\">\n");
    for a in &cell_arrays {
        array_tag(&mut x, a, enc, &mut offset, &mut appended);
    }
    x.push_str("      </CellData>\n      <Points>\n");
    array_tag(&mut x, &points, enc, &mut offset, &mut appended);
    x.push_str("      </Points>\n      <Cells>\n");
    for a in &cells {
        array_tag(&mut x, a, enc, &mut offset, &mut appended);
    }
    x.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n");
    w.write_all(x.as_bytes())?;
    if opts.encoding == VtuEncoding::AppendedRaw {
        w.write_all(b"  <AppendedData encoding=\"raw\">\n   _")?;
        for a in appended {
            w.write_all(&(a.bytes.len() as u64).to_le_bytes())?;
            w.write_all(&a.bytes)?;
        }
        w.write_all(b"\n  </AppendedData>\n")?;
    }
    w.write_all(b"</VTKFile>\n")
}

// ---------------------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------------------

/// One `<DataArray>` found in the XML part.
struct DataArray {
    section: &'static str,
    name: String,
    ty: String,
    ncomp: usize,
    format: String,
    offset: Option<u64>,
    /// Byte range of the element's text content.
    text: (usize, usize),
    /// Byte position of the tag, for errors.
    at: usize,
}

fn attr(tag: &str, name: &str) -> Option<String> {
    let mut rest = tag;
    loop {
        let i = rest.find(name)?;
        let before_ok = i == 0 || rest.as_bytes()[i - 1].is_ascii_whitespace();
        let after = rest[i + name.len()..].trim_start();
        if before_ok && let Some(v) = after.strip_prefix('=') {
            let v = v.trim_start();
            let q = v.chars().next()?;
            if q == '"' || q == '\'' {
                let end = v[1..].find(q)?;
                return Some(v[1..1 + end].to_string());
            }
            return None;
        }
        rest = &rest[i + name.len()..];
    }
}

struct Vtu<'a> {
    data: &'a [u8],
    file: String,
    header64: bool,
    compressed: bool,
    appended: Option<(usize, bool)>,
}

impl Vtu<'_> {
    fn err(&self, at: usize, msg: impl Into<String>) -> Error {
        Error::Syntax {
            file: self.file.clone(),
            at: Location::Byte(at as u64),
            msg: msg.into(),
        }
    }

    fn type_size(&self, a: &DataArray) -> Result<usize> {
        Ok(match a.ty.as_str() {
            "Int8" | "UInt8" => 1,
            "Int16" | "UInt16" => 2,
            "Int32" | "UInt32" | "Float32" => 4,
            "Int64" | "UInt64" | "Float64" => 8,
            t => return Err(self.err(a.at, format!("DataArray {}: unsupported type {t}", a.name))),
        })
    }

    /// Decodes a little-endian binary block into numbers.
    fn decode(&self, a: &DataArray, raw: &[u8]) -> Result<Vec<f64>> {
        let sz = self.type_size(a)?;
        if !raw.len().is_multiple_of(sz) {
            return Err(self.err(
                a.at,
                format!(
                    "DataArray {}: {} bytes is not a multiple of {sz}",
                    a.name,
                    raw.len()
                ),
            ));
        }
        let mut out = Vec::with_capacity(raw.len() / sz);
        for c in raw.chunks_exact(sz) {
            let v = match a.ty.as_str() {
                "Int8" => f64::from(c[0] as i8),
                "UInt8" => f64::from(c[0]),
                "Int16" => f64::from(i16::from_le_bytes([c[0], c[1]])),
                "UInt16" => f64::from(u16::from_le_bytes([c[0], c[1]])),
                "Int32" => f64::from(i32::from_le_bytes(c.try_into().expect("4 bytes"))),
                "UInt32" => f64::from(u32::from_le_bytes(c.try_into().expect("4 bytes"))),
                "Float32" => f64::from(f32::from_le_bytes(c.try_into().expect("4 bytes"))),
                "Int64" => i64::from_le_bytes(c.try_into().expect("8 bytes")) as f64,
                "UInt64" => u64::from_le_bytes(c.try_into().expect("8 bytes")) as f64,
                _ => f64::from_le_bytes(c.try_into().expect("8 bytes")),
            };
            out.push(v);
        }
        Ok(out)
    }

    fn header_len(&self) -> usize {
        if self.header64 { 8 } else { 4 }
    }

    fn read_header(&self, b: &[u8], at: usize) -> Result<usize> {
        let h = self.header_len();
        if b.len() < h {
            return Err(Error::Truncated {
                file: self.file.clone(),
                at: Location::Byte(at as u64),
                what: "a data block header".into(),
            });
        }
        let v = if self.header64 {
            u64::from_le_bytes(b[..8].try_into().expect("8 bytes"))
        } else {
            u64::from(u32::from_le_bytes(b[..4].try_into().expect("4 bytes")))
        };
        usize::try_from(v).map_err(|_| self.err(at, "block size too large"))
    }

    /// Word `k` of a block header.
    fn word(&self, b: &[u8], k: usize, at: usize) -> Result<usize> {
        let h = self.header_len();
        self.read_header(b.get(k * h..).unwrap_or(&[]), at)
    }

    /// Inflates the blocks of a zlib-compressed array: `header` holds
    /// `[nblocks, blocksize, lastsize, csize_1..csize_n]`, `body` the compressed blocks.
    fn inflate(&self, a: &DataArray, header: &[u8], body: &[u8]) -> Result<Vec<u8>> {
        use std::io::Read as _;
        let nb = self.word(header, 0, a.at)?;
        let mut out = Vec::new();
        let mut pos = 0usize;
        for k in 0..nb {
            let c = self.word(header, 3 + k, a.at)?;
            let end = pos
                .checked_add(c)
                .filter(|&e| e <= body.len())
                .ok_or_else(|| Error::Truncated {
                    file: self.file.clone(),
                    at: Location::Byte(a.at as u64),
                    what: format!("compressed block {k} of {}", a.name),
                })?;
            flate2::read::ZlibDecoder::new(&body[pos..end])
                .read_to_end(&mut out)
                .map_err(|e| self.err(a.at, format!("DataArray {}: block {k}: {e}", a.name)))?;
            pos = end;
        }
        Ok(out)
    }

    /// Number of header bytes of a compressed array whose header starts `b`.
    fn compressed_header_len(&self, b: &[u8], at: usize) -> Result<usize> {
        let nb = self.word(b, 0, at)?;
        nb.checked_add(3)
            .and_then(|w| w.checked_mul(self.header_len()))
            .filter(|&n| n <= self.data.len())
            .ok_or_else(|| self.err(at, format!("{nb} compressed blocks announced")))
    }

    /// The values of an array, whatever its format.
    fn values(&self, a: &DataArray) -> Result<Vec<f64>> {
        match a.format.as_str() {
            "ascii" => {
                let t = &self.data[a.text.0..a.text.1];
                let mut out = Vec::new();
                for tok in t
                    .split(|c| c.is_ascii_whitespace())
                    .filter(|t| !t.is_empty())
                {
                    let v = crate::text::parse_f64(tok).ok_or_else(|| {
                        self.err(
                            a.at,
                            format!(
                                "DataArray {}: '{}' is not a number",
                                a.name,
                                String::from_utf8_lossy(tok)
                            ),
                        )
                    })?;
                    out.push(v);
                }
                Ok(out)
            }
            "binary" if self.compressed => {
                let t: Vec<u8> = self.data[a.text.0..a.text.1]
                    .iter()
                    .copied()
                    .filter(|c| !c.is_ascii_whitespace())
                    .collect();
                let h = self.header_len();
                let dec = |x: &[u8]| {
                    B64.decode(x)
                        .map_err(|e| self.err(a.at, format!("DataArray {}: {e}", a.name)))
                };
                let first = dec(t.get(..(3 * h).div_ceil(3) * 4).unwrap_or(&t))?;
                let hl = self.compressed_header_len(&first, a.at)?;
                let hc = hl.div_ceil(3) * 4;
                if t.len() < hc {
                    return Err(
                        self.err(a.at, format!("DataArray {}: base64 data too short", a.name))
                    );
                }
                let header = dec(&t[..hc])?;
                let body = dec(&t[hc..])?;
                let raw = self.inflate(a, &header, &body)?;
                self.decode(a, &raw)
            }
            "binary" => {
                let t: Vec<u8> = self.data[a.text.0..a.text.1]
                    .iter()
                    .copied()
                    .filter(|c| !c.is_ascii_whitespace())
                    .collect();
                let h = self.header_len();
                // The header is encoded on its own or together with the data; try both.
                let all = B64.decode(&t).ok();
                let raw = match all {
                    Some(all)
                        if all.len() >= h && self.read_header(&all, a.at)? == all.len() - h =>
                    {
                        all[h..].to_vec()
                    }
                    _ => {
                        let hl = (h * 4).div_ceil(3).div_ceil(4) * 4;
                        if t.len() < hl {
                            return Err(self.err(
                                a.at,
                                format!("DataArray {}: base64 data too short", a.name),
                            ));
                        }
                        let head = B64
                            .decode(&t[..hl])
                            .map_err(|e| self.err(a.at, format!("DataArray {}: {e}", a.name)))?;
                        let n = self.read_header(&head, a.at)?;
                        let body = B64
                            .decode(&t[hl..])
                            .map_err(|e| self.err(a.at, format!("DataArray {}: {e}", a.name)))?;
                        if body.len() < n {
                            return Err(self.err(
                                a.at,
                                format!(
                                    "DataArray {}: {} bytes announced, {} found",
                                    a.name,
                                    n,
                                    body.len()
                                ),
                            ));
                        }
                        body[..n].to_vec()
                    }
                };
                self.decode(a, &raw)
            }
            "appended" => {
                let (start, raw_enc) = self
                    .appended
                    .ok_or_else(|| self.err(a.at, "appended array without <AppendedData>"))?;
                let off = a
                    .offset
                    .ok_or_else(|| self.err(a.at, format!("DataArray {}: no offset", a.name)))?;
                let pos = start
                    .checked_add(off as usize)
                    .filter(|&p| p <= self.data.len())
                    .ok_or_else(|| Error::Truncated {
                        file: self.file.clone(),
                        at: Location::Byte(self.data.len() as u64),
                        what: format!("appended data of {}", a.name),
                    })?;
                if raw_enc && self.compressed {
                    let hl = self.compressed_header_len(&self.data[pos..], pos)?;
                    let header = self
                        .data
                        .get(pos..pos + hl)
                        .ok_or_else(|| Error::Truncated {
                            file: self.file.clone(),
                            at: Location::Byte(self.data.len() as u64),
                            what: format!("appended data of {}", a.name),
                        })?;
                    let raw = self.inflate(a, header, &self.data[pos + hl..])?;
                    self.decode(a, &raw)
                } else if raw_enc {
                    let n = self.read_header(&self.data[pos..], pos)?;
                    let h = self.header_len();
                    let end = pos
                        .checked_add(h + n)
                        .filter(|&e| e <= self.data.len())
                        .ok_or_else(|| Error::Truncated {
                            file: self.file.clone(),
                            at: Location::Byte(self.data.len() as u64),
                            what: format!("appended data of {}", a.name),
                        })?;
                    self.decode(a, &self.data[pos + h..end])
                } else {
                    Err(self.err(
                        a.at,
                        "base64-encoded appended data is not supported; use raw or inline binary",
                    ))
                }
            }
            f => Err(self.err(a.at, format!("DataArray {}: unknown format '{f}'", a.name))),
        }
    }
}

/// One `<PointData>` array of a VTU file ([`read_with_point_data`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PointArray {
    /// Its `Name`.
    pub name: String,
    /// Its `NumberOfComponents` (1 for a scalar).
    pub components: usize,
    /// The values point by point, the components of a point contiguous, as f64.
    pub values: Vec<f64>,
}

impl PointArray {
    /// The value of point `i` (its `components` numbers).
    pub fn at(&self, i: usize) -> &[f64] {
        &self.values[i * self.components..(i + 1) * self.components]
    }
}

/// Reads a VTK XML unstructured grid from `r`; `file` names the input in errors. Point and
/// cell data other than the `marker` cell array are not read ([`read_with_point_data`]
/// reads the point data).
pub fn read<R: Read>(r: R, file: &Path) -> Result<Mesh> {
    read_impl(r, file, false).map(|(m, _)| m)
}

/// [`read`], also returning every `<PointData>` array, in the file's order, each checked to
/// hold one tuple per point (an error naming the array otherwise).
pub fn read_with_point_data<R: Read>(r: R, file: &Path) -> Result<(Mesh, Vec<PointArray>)> {
    read_impl(r, file, true)
}

fn read_impl<R: Read>(mut r: R, file: &Path, point_data: bool) -> Result<(Mesh, Vec<PointArray>)> {
    let file = file.display().to_string();
    let mut data = Vec::new();
    r.read_to_end(&mut data).map_err(|source| Error::Io {
        file: file.clone(),
        error: source,
    })?;
    let xml_end = find(&data, b"<AppendedData").unwrap_or(data.len());
    let mut vtu = Vtu {
        data: &data,
        file: file.clone(),
        header64: false,
        compressed: false,
        appended: None,
    };
    // Tag scan over the XML part.
    let mut arrays: Vec<DataArray> = Vec::new();
    let mut section: &'static str = "";
    let mut n_points: Option<usize> = None;
    let mut n_cells: Option<usize> = None;
    let mut pos = 0;
    let mut seen_vtk = false;
    while let Some(lt) = find(&data[pos..xml_end], b"<") {
        let start = pos + lt;
        let gt = find(&data[start..xml_end], b">").ok_or_else(|| Error::Truncated {
            file: file.clone(),
            at: Location::Byte(start as u64),
            what: "an XML tag".into(),
        })?;
        let tag = String::from_utf8_lossy(&data[start + 1..start + gt]).into_owned();
        pos = start + gt + 1;
        let name = tag.split_whitespace().next().unwrap_or("").to_string();
        match name.as_str() {
            "VTKFile" => {
                seen_vtk = true;
                let ty = attr(&tag, "type").unwrap_or_default();
                if ty != "UnstructuredGrid" {
                    return Err(vtu.err(
                        start,
                        format!("VTKFile type '{ty}' (expected UnstructuredGrid)"),
                    ));
                }
                match attr(&tag, "compressor").as_deref() {
                    None => {}
                    Some("vtkZLibDataCompressor") => vtu.compressed = true,
                    Some(c) => {
                        return Err(vtu.err(
                            start,
                            format!("compressor {c} is not supported (only zlib)"),
                        ));
                    }
                }
                if attr(&tag, "byte_order").is_some_and(|b| b != "LittleEndian") {
                    return Err(vtu.err(start, "big-endian VTU files are not supported"));
                }
                vtu.header64 = attr(&tag, "header_type").is_some_and(|h| h == "UInt64");
            }
            "Piece" => {
                if n_points.is_some() {
                    return Err(vtu.err(start, "more than one <Piece> is not supported"));
                }
                let num = |a: &str| attr(&tag, a).and_then(|v| v.parse::<usize>().ok());
                n_points = Some(
                    num("NumberOfPoints")
                        .ok_or_else(|| vtu.err(start, "Piece without NumberOfPoints"))?,
                );
                n_cells = Some(
                    num("NumberOfCells")
                        .ok_or_else(|| vtu.err(start, "Piece without NumberOfCells"))?,
                );
            }
            "Points" => section = "Points",
            "Cells" => section = "Cells",
            "PointData" => section = "PointData",
            "CellData" => section = "CellData",
            "FieldData" => section = "FieldData",
            "/Points" | "/Cells" | "/PointData" | "/CellData" | "/FieldData" => section = "",
            "DataArray" => {
                let self_closing = tag.trim_end().ends_with('/');
                let text = if self_closing {
                    (pos, pos)
                } else {
                    let close = find(&data[pos..xml_end], b"</DataArray>").ok_or_else(|| {
                        Error::Truncated {
                            file: file.clone(),
                            at: Location::Byte(start as u64),
                            what: "a DataArray".into(),
                        }
                    })?;
                    let t = (pos, pos + close);
                    pos += close + b"</DataArray>".len();
                    t
                };
                arrays.push(DataArray {
                    section,
                    name: attr(&tag, "Name").unwrap_or_default(),
                    ty: attr(&tag, "type").unwrap_or_default(),
                    ncomp: attr(&tag, "NumberOfComponents")
                        .and_then(|v| v.parse().ok())
                        .unwrap_or(1),
                    format: attr(&tag, "format").unwrap_or_else(|| "ascii".into()),
                    offset: attr(&tag, "offset").and_then(|v| v.parse().ok()),
                    text,
                    at: start,
                });
            }
            _ => {}
        }
    }
    if !seen_vtk {
        return Err(vtu.err(0, "not a VTK XML file (no <VTKFile>)"));
    }
    let tail = &data[data.len().saturating_sub(1024)..];
    if find(tail, b"</VTKFile>").is_none() {
        return Err(Error::Truncated {
            file: file.clone(),
            at: Location::Byte(data.len() as u64),
            what: "the file (no closing </VTKFile>)".into(),
        });
    }
    if xml_end < data.len() {
        let gt = find(&data[xml_end..], b">")
            .ok_or_else(|| vtu.err(xml_end, "unterminated <AppendedData>"))?;
        let tag = String::from_utf8_lossy(&data[xml_end..xml_end + gt]).into_owned();
        let raw = attr(&tag, "encoding").is_some_and(|e| e == "raw");
        let us = find(&data[xml_end + gt..], b"_")
            .ok_or_else(|| vtu.err(xml_end, "no '_' marker in <AppendedData>"))?;
        vtu.appended = Some((xml_end + gt + us + 1, raw));
    }
    let (Some(np), Some(nc)) = (n_points, n_cells) else {
        return Err(Error::Truncated {
            file,
            at: Location::End,
            what: "the grid (no <Piece>)".into(),
        });
    };
    let get = |sec: &str, name: Option<&str>| {
        arrays
            .iter()
            .find(|a| a.section == sec && name.is_none_or(|n| a.name == n))
    };
    let pts = get("Points", None).ok_or_else(|| vtu.err(0, "no <Points> array"))?;
    let pv = vtu.values(pts)?;
    if pts.ncomp != 3 || Some(pv.len()) != np.checked_mul(3) {
        return Err(vtu.err(
            pts.at,
            format!(
                "Points: {} values for {np} points of {} components",
                pv.len(),
                pts.ncomp
            ),
        ));
    }
    if let Some(i) = pv.iter().position(|x| !x.is_finite()) {
        return Err(vtu.err(
            pts.at,
            format!("Points: node {} has a non-finite coordinate", i / 3),
        ));
    }
    let mut pdata = Vec::new();
    for a in arrays
        .iter()
        .filter(|a| point_data && a.section == "PointData")
    {
        let values = vtu.values(a)?;
        if a.ncomp == 0 || Some(values.len()) != np.checked_mul(a.ncomp) {
            return Err(vtu.err(
                a.at,
                format!(
                    "PointData {}: {} values for {np} points of {} components",
                    a.name,
                    values.len(),
                    a.ncomp
                ),
            ));
        }
        pdata.push(PointArray {
            name: a.name.clone(),
            components: a.ncomp,
            values,
        });
    }
    let conn_a =
        get("Cells", Some("connectivity")).ok_or_else(|| vtu.err(0, "no connectivity array"))?;
    let offs_a = get("Cells", Some("offsets")).ok_or_else(|| vtu.err(0, "no offsets array"))?;
    let types_a = get("Cells", Some("types")).ok_or_else(|| vtu.err(0, "no types array"))?;
    let conn = vtu.values(conn_a)?;
    let offs = vtu.values(offs_a)?;
    let types = vtu.values(types_a)?;
    if offs.len() != nc || types.len() != nc {
        return Err(vtu.err(
            offs_a.at,
            format!(
                "{} offsets and {} types for {nc} cells",
                offs.len(),
                types.len()
            ),
        ));
    }
    let marker_ids = match get("CellData", Some("marker")) {
        Some(a) => {
            let v = vtu.values(a)?;
            if v.len() != nc {
                return Err(vtu.err(a.at, format!("marker: {} values for {nc} cells", v.len())));
            }
            Some(v)
        }
        None => None,
    };
    let mut names: Vec<(i64, String)> = arrays
        .iter()
        .filter(|a| a.section == "FieldData" && a.name.starts_with("marker:"))
        .filter_map(|a| {
            let v = vtu.values(a).ok()?;
            Some((*v.first()? as i64, a.name["marker:".len()..].to_string()))
        })
        .collect();
    names.sort();
    // Cells.
    let mut kinds = Vec::with_capacity(nc);
    let mut prev = 0usize;
    for (i, (&t, &o)) in types.iter().zip(&offs).enumerate() {
        let kind =
            ElementKind::from_vtk_code(t as i64).ok_or_else(|| Error::UnknownElementType {
                file: file.clone(),
                at: Location::Byte(types_a.at as u64),
                code: t as i64,
            })?;
        let o = o as usize;
        if o < prev || o - prev != kind.n_nodes() || o > conn.len() {
            return Err(vtu.err(
                offs_a.at,
                format!(
                    "cell {i}: offset {o} inconsistent with a {} after offset {prev}",
                    kind.name()
                ),
            ));
        }
        prev = o;
        kinds.push(kind);
    }
    let dim = kinds.iter().map(|k| k.dim()).max().unwrap_or(3).max(2);
    let mut mesh = Mesh::new(dim);
    mesh.coords = pv.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let mut marker_sets: std::collections::BTreeMap<i64, Elements> = Default::default();
    let mut dropped = 0;
    let mut nodes = [0u32; 8];
    let mut start = 0usize;
    for (i, kind) in kinds.iter().enumerate() {
        let nn = kind.n_nodes();
        for k in 0..nn {
            let v = conn[start + k];
            if !(v >= 0.0 && (v as usize) < np) || v.fract() != 0.0 {
                return Err(Error::NodeOutOfRange {
                    file: file.clone(),
                    at: Location::Byte(conn_a.at as u64),
                    node: v.max(0.0) as u64,
                    n_nodes: np,
                });
            }
            nodes[k] = v as u32;
        }
        start += nn;
        let id = marker_ids.as_ref().map_or(0, |m| m[i] as i64);
        if kind.dim() == dim && id == 0 {
            mesh.cells.push(*kind, &nodes[..nn], None);
        } else if kind.dim() + 1 == dim {
            marker_sets
                .entry(id)
                .or_default()
                .push(*kind, &nodes[..nn], None);
        } else {
            dropped += 1;
        }
    }
    if dropped > 0 {
        mesh.warnings.push(format!(
            "{file}: {dropped} cells of other dimensions dropped"
        ));
    }
    for (id, elements) in marker_sets {
        let name = names
            .iter()
            .find(|(k, _)| *k == id)
            .map_or_else(|| format!("marker_{id}"), |(_, n)| n.clone());
        mesh.markers.push(Marker {
            name,
            tag: None,
            elements,
        });
    }
    Ok((mesh, pdata))
}

fn find(h: &[u8], n: &[u8]) -> Option<usize> {
    h.windows(n.len()).position(|w| w == n)
}
