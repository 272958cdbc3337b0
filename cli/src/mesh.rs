//! `gradvi mesh`: statistics of a mesh file, generated meshes and format conversion, in 2D and
//! 3D.
//!
//! The dimension of a file comes from its format: `.typ1` and `.typ2` are 2D; `.vtu`, `.node`,
//! `.ele` and the stem of a `.node`/`.ele` pair (HArDCore's RF format) are 3D; a gmsh `.msh`
//! file is 3D when it has 3D elements (tetrahedra, hexahedra, prisms or pyramids), else 2D
//! ([`gradvi::case::read_any`]). Generated meshes are 3D for the family names of
//! [`Family3`] (cubes, kuhn or tetrahedra, prisms, refined, warped) and 2D for those of
//! [`Family`] (cartesian, hexagonal, kershaw, triangles). The faces of a 3D mesh that are not
//! planar are kept whole or split into triangles as `--warped-faces` says ([`WarpedFaces`]).
//! 3D meshes are written as `.vtu` only
//! (`.typ2` is a 2D format); every output is written atomically and never over an input
//! ([`crate::output`]).

use crate::output;
use anyhow::{Result, bail};
use clap::Subcommand;
use clap::builder::{PossibleValuesParser, TypedValueParser};
use gradvi::budget::MemoryBudget;
use gradvi::case::{AnyMesh, read_any};
use gradvi::mesh::generate::Family;
use gradvi::mesh::io::{write_typ2, write_vtu};
use gradvi::mesh::{PolyMesh, Rect};
use gradvi::mesh3d::generate::Family3;
use gradvi::mesh3d::io::write_vtu3;
use gradvi::mesh3d::{Cuboid, PolyMesh3, WarpedFaces};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The `gradvi mesh` subcommands.
#[derive(Subcommand)]
pub enum MeshCommand {
    /// Print the statistics of a mesh file: 2D (.msh of triangles and quadrangles, .typ1,
    /// .typ2) or 3D (.msh of tetrahedra, hexahedra, prisms and pyramids; HArDCore RF .node and
    /// .ele, or their common stem; .vtu).
    Info {
        /// The mesh file.
        file: PathBuf,
        /// 3D: how faces that are not planar are represented (see --warped-faces of
        /// `gradvi mesh generate`).
        #[arg(long, default_value = "fan", value_parser = warped_faces())]
        warped_faces: WarpedFaces,
    },
    /// Generate a mesh of the unit square (2D families) or the unit cube (3D families), or of
    /// --domain, and write it (.typ2 or .vtu in 2D, .vtu in 3D, by extension).
    Generate {
        /// 2D: cartesian, hexagonal, kershaw or triangles. 3D: cubes, kuhn (or tetrahedra),
        /// prisms, refined or warped.
        family: String,
        /// Level (hexagonal k: the FVCA5 hexa1_k mesh; kershaw k: mesh4_1_k; cartesian k:
        /// 2^(k+1) × 2^(k+1) squares; triangles k: those squares, each cut into two triangles
        /// by its diagonal from lower left to upper right; the 3D families have 2^(k+1) cubes
        /// per side, cut into 6 Kuhn tetrahedra or 2 prisms, a checkerboard of them split into
        /// 8, or randomly perturbed).
        #[arg(long)]
        level: usize,
        /// The domain: x0 x1 y0 y1 (2D) or x0 x1 y0 y1 z0 z1 (3D).
        #[arg(long, num_args = 4..=6, allow_negative_numbers = true, value_name = "BOUND")]
        domain: Option<Vec<f64>>,
        /// Output file (.typ2 or .vtu in 2D, .vtu in 3D).
        #[arg(short, long)]
        output: PathBuf,
        /// 3D: how faces that are not planar (the warped family's) are represented: fan (one
        /// face measured on the triangles fanned from its vertex average, HArDCore3D's
        /// convention; HMM is then exact on affine functions only up to the warp) or split
        /// (each such face split into those triangles around a new vertex; HMM exact, one
        /// unknown per triangle). No effect in 2D.
        #[arg(long, default_value = "fan", value_parser = warped_faces())]
        warped_faces: WarpedFaces,
    },
    /// Read a mesh, validate it and write it in another format: 2D to .typ2 or .vtu, 3D (gmsh,
    /// RF, VTU) to .vtu.
    Convert {
        /// The mesh file (as for `gradvi mesh info`).
        input: PathBuf,
        /// The output file.
        output: PathBuf,
        /// 3D: fan or split (see --warped-faces of `gradvi mesh generate`).
        #[arg(long, default_value = "fan", value_parser = warped_faces())]
        warped_faces: WarpedFaces,
    },
}

/// The parser of `--warped-faces`: `fan` or `split` ([`WarpedFaces`]).
pub fn warped_faces() -> impl TypedValueParser<Value = WarpedFaces> {
    PossibleValuesParser::new(WarpedFaces::ALL.map(WarpedFaces::name))
        .try_map(|s| s.parse::<WarpedFaces>())
}

/// Runs a `gradvi mesh` subcommand.
pub fn run(c: &MeshCommand) -> Result<()> {
    match c {
        MeshCommand::Info { file, warped_faces } => match read(file, *warped_faces)? {
            AnyMesh::Two(m) => info_2d(file, &m),
            AnyMesh::Three(m) => info_3d(file, &m),
        },
        MeshCommand::Generate {
            family,
            level,
            domain,
            output,
            warped_faces,
        } => {
            // the output format is checked before any work
            check_format(family.parse::<Family3>().is_ok(), output)?;
            let m = generate(family, *level, domain.as_deref(), *warped_faces)?;
            write(&m, output)?;
            eprintln!(
                "wrote {} ({} cells, h = {:.6})",
                output.display(),
                m.n_cells(),
                m.h()
            );
            Ok(())
        }
        MeshCommand::Convert {
            input,
            output,
            warped_faces,
        } => {
            output::check_distinct(&[("mesh", input)], &[("converted mesh", output)])?;
            let m = read(input, *warped_faces)?;
            write(&m, output)?;
            eprintln!("wrote {} ({} cells)", output.display(), m.n_cells());
            Ok(())
        }
    }
}

/// The mesh in `path`, 2D or 3D by its format ([`read_any`]), within the memory available.
fn read(path: &Path, warped: WarpedFaces) -> Result<AnyMesh> {
    Ok(read_any(path, warped, MemoryBudget::available())?)
}

/// The mesh of `family` at `level`, on `domain` (4 bounds in 2D, 6 in 3D) or the unit square
/// or cube; a 3D mesh's warped faces as `warped` says.
fn generate(
    family: &str,
    level: usize,
    domain: Option<&[f64]>,
    warped: WarpedFaces,
) -> Result<AnyMesh> {
    let budget = MemoryBudget::available();
    if let Ok(f) = family.parse::<Family3>() {
        let cuboid = match domain {
            None => Cuboid::UNIT,
            Some(&[x0, x1, y0, y1, z0, z1]) => Cuboid::new([x0, x1], [y0, y1], [z0, z1]),
            Some(d) => bail!(
                "--domain of the 3D family {f} needs 6 bounds (x0 x1 y0 y1 z0 z1), got {}",
                d.len()
            ),
        };
        let m = f.generate_on(level, cuboid, budget)?;
        return Ok(AnyMesh::Three(warped.apply(m, budget)?));
    }
    let f = match family.parse::<Family>() {
        Ok(f) => f,
        // the 2D list, then the 3D one
        Err(e) => bail!(
            "{e} (2D), or one of \"cubes\", \"kuhn\" (or \"tetrahedra\"), \"prisms\", \
             \"refined\" or \"warped\" (3D)"
        ),
    };
    Ok(AnyMesh::Two(match domain {
        None => f.generate(level, budget)?,
        Some(&[x0, x1, y0, y1]) => f.generate_on(level, Rect::new([x0, x1], [y0, y1]), budget)?,
        Some(d) => bail!(
            "--domain of the 2D family {f} needs 4 bounds (x0 x1 y0 y1), got {}",
            d.len()
        ),
    }))
}

/// The extension of `out`, lowercase, if it is a format a mesh of this dimension (3D if
/// `three`) is written in: `.typ2` or `.vtu` in 2D, `.vtu` in 3D.
fn check_format(three: bool, out: &Path) -> Result<String> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match (three, ext.as_str()) {
        (false, "typ2" | "vtu") | (true, "vtu") => Ok(ext),
        (false, _) => bail!(
            "unknown output format for {} (use .typ2 or .vtu)",
            out.display()
        ),
        (true, "typ2") => bail!(
            "cannot write a 3D mesh to {}: .typ2 is a 2D format (use .vtu)",
            out.display()
        ),
        (true, _) => bail!(
            "unknown output format for the 3D mesh {} (use .vtu)",
            out.display()
        ),
    }
}

/// Writes `m` to `out` atomically, in the format of its extension ([`check_format`]).
fn write(m: &AnyMesh, out: &Path) -> Result<()> {
    let ext = check_format(matches!(m, AnyMesh::Three(_)), out)?;
    match m {
        AnyMesh::Two(m) if ext == "typ2" => output::atomic(out, |tmp| Ok(write_typ2(tmp, m)?)),
        AnyMesh::Two(m) => output::atomic(out, |tmp| Ok(write_vtu(tmp, m, &[], &[])?)),
        AnyMesh::Three(m) => {
            output::atomic(out, |tmp| Ok(write_vtu3(tmp, &m.to_polyhedra(), &[], &[])?))
        }
    }
}

/// `size:count` pairs, space-separated ("3:128 4:2").
fn counts(c: &BTreeMap<usize, usize>) -> String {
    let s: Vec<String> = c.iter().map(|(n, c)| format!("{n}:{c}")).collect();
    s.join(" ")
}

/// `tag t: count` pairs, comma-separated ("tag 0: 4, tag 10: 2").
fn tag_counts(c: &BTreeMap<i32, usize>) -> String {
    let s: Vec<String> = c.iter().map(|(t, c)| format!("tag {t}: {c}")).collect();
    s.join(", ")
}

fn info_2d(file: &Path, m: &PolyMesh) -> Result<()> {
    let mut sides = BTreeMap::new();
    for k in 0..m.n_cells() {
        *sides.entry(m.cell_vertices(k).len()).or_insert(0usize) += 1;
    }
    let area: f64 = (0..m.n_cells()).map(|k| m.measure(k)).sum();
    let bb = m.bounding_box();
    let mut tags = BTreeMap::new();
    for &e in m.boundary_edges() {
        *tags.entry(m.edge_tag(e)).or_insert(0usize) += 1;
    }
    println!("file            {}", file.display());
    println!("cells           {}", m.n_cells());
    println!("vertices        {}", m.n_vertices());
    println!(
        "edges           {} ({} on the boundary)",
        m.n_edges(),
        m.boundary_edges().len()
    );
    println!("h (max diam.)   {:.6}", m.h());
    println!("total area      {area:.12}");
    println!(
        "bounding box    [{}, {}] x [{}, {}]",
        bb.x[0], bb.x[1], bb.y[0], bb.y[1]
    );
    println!("cells by sides  {}", counts(&sides));
    println!("boundary edges  {}", tag_counts(&tags));
    Ok(())
}

fn info_3d(file: &Path, m: &PolyMesh3) -> Result<()> {
    let mut faces = BTreeMap::new();
    let mut cell_tags = BTreeMap::new();
    for k in 0..m.n_cells() {
        *faces.entry(m.cell_faces(k).len()).or_insert(0usize) += 1;
        *cell_tags.entry(m.cell_tag(k)).or_insert(0usize) += 1;
    }
    let mut face_tags = BTreeMap::new();
    for &f in m.boundary_faces() {
        *face_tags.entry(m.face_tag(f as usize)).or_insert(0usize) += 1;
    }
    let volume: f64 = (0..m.n_cells()).map(|k| m.measure(k)).sum();
    let warp = (0..m.n_faces()).map(|f| m.face_warp(f)).fold(0.0, f64::max);
    let [x, y, z] = m.bounding_box().ranges();
    println!("file            {}", file.display());
    println!("dimension       3");
    println!("cells           {}", m.n_cells());
    println!("vertices        {}", m.n_vertices());
    println!(
        "faces           {} ({} on the boundary)",
        m.n_faces(),
        m.boundary_faces().len()
    );
    println!("h (max diam.)   {:.6}", m.h());
    println!("total volume    {volume:.12}");
    println!(
        "bounding box    [{}, {}] x [{}, {}] x [{}, {}]",
        x[0], x[1], y[0], y[1], z[0], z[1]
    );
    println!("cells by faces  {}", counts(&faces));
    println!("max face warp   {warp:.3e}");
    println!("cell tags       {}", tag_counts(&cell_tags));
    println!("boundary faces  {}", tag_counts(&face_tags));
    Ok(())
}
