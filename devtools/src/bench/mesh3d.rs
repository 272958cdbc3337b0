//! The 3D mesh benchmark (`gradvi-dev bench --mesh3d`): reading and building tetrahedral gmsh
//! meshes of the unit cube (issue 32, "Cost").
//!
//! For each target size in [`TARGETS`] up to `GRADVI_BENCH_MAX_CELLS` (default
//! [`super::DEFAULT_MAX_CELLS`]), gmsh meshes the unit cube into about that many tetrahedra
//! (`-3`, one thread, msh 4.1, one physical volume and one physical surface for the six
//! sides) into `target/bench-meshes/cube3d_N.msh` (reused when present, not committed). Each
//! mesh is then read ([`read_mesh3`]) and built ([`PolyMesh3::from_polyhedra`]) in a child
//! process (`gradvi-dev bench --mesh3d-child FILE`), so that its peak resident memory is that
//! of the case alone, and one line per mesh is printed: cells, faces, read and build times,
//! time per cell and peak memory. Nothing is written to the repository; the numbers recorded
//! by hand go to `replication/measurements/mesh3d_io.md`.

use super::{bad, io_err, peak_memory_mib, stdout_of};
use gradvi::budget::MemoryBudget;
use gradvi::mesh3d::PolyMesh3;
use gradvi::mesh3d::io::read_mesh3;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

/// Target numbers of tetrahedra.
pub const TARGETS: [usize; 4] = [10_000, 100_000, 300_000, 1_000_000];

/// gmsh mesh size for about `n` tetrahedra in the unit cube (calibrated: 0.0166 gives
/// 1 014 275 tetrahedra; the count goes as the inverse cube of the size).
pub fn mesh_size(n: usize) -> f64 {
    0.0166 * (1_014_275.0 / n as f64).cbrt()
}

/// What a child measures on one mesh.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Mesh3Row {
    /// The mesh file.
    pub file: String,
    /// Cells of the built mesh.
    pub cells: usize,
    /// Faces of the built mesh.
    pub faces: usize,
    /// Vertices of the built mesh.
    pub vertices: usize,
    /// [`read_mesh3`], seconds.
    pub read_s: f64,
    /// [`PolyMesh3::from_polyhedra`], seconds.
    pub build_s: f64,
    /// Peak resident memory of the child (`VmHWM`), MiB.
    pub peak_mib: f64,
}

/// Reads and builds `file` in this process and returns the row (the body of a child).
pub fn run_one(file: &Path) -> gradvi::Result<Mesh3Row> {
    let budget = MemoryBudget::available();
    let t0 = Instant::now();
    let p = read_mesh3(file, budget)?;
    let read_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let m = PolyMesh3::from_file_polyhedra(p, budget, gradvi::mesh3d::WarpedFaces::default())?;
    let build_s = t1.elapsed().as_secs_f64();
    Ok(Mesh3Row {
        file: file.display().to_string(),
        cells: m.n_cells(),
        faces: m.n_faces(),
        vertices: m.n_vertices(),
        read_s,
        build_s,
        peak_mib: peak_memory_mib(),
    })
}

/// `--mesh3d-child FILE`: runs [`run_one`] and prints its row as JSON.
pub fn child_main(args: &[String]) -> gradvi::Result<()> {
    let file = args
        .first()
        .ok_or_else(|| bad("--mesh3d-child FILE".into()))?;
    let row = run_one(Path::new(file))?;
    println!(
        "{}",
        serde_json::to_string(&row).map_err(|e| bad(e.to_string()))?
    );
    Ok(())
}

/// Writes (or reuses) the gmsh mesh of the unit cube with about `n` tetrahedra in `dir`.
pub fn cube_mesh(dir: &Path, n: usize) -> gradvi::Result<PathBuf> {
    std::fs::create_dir_all(dir).map_err(|e| io_err(dir, e))?;
    let geo = format!(
        "SetFactory(\"OpenCASCADE\");\nBox(1) = {{0, 0, 0, 1, 1, 1}};\n\
         Physical Volume(1) = {{1}};\nPhysical Surface(2) = {{1, 2, 3, 4, 5, 6}};\n\
         Mesh.MeshSizeMin = {h:.6e};\nMesh.MeshSizeMax = {h:.6e};\n",
        h = mesh_size(n)
    );
    let geo_path = dir.join(format!("cube3d_{n}.geo"));
    let msh_path = dir.join(format!("cube3d_{n}.msh"));
    let same_geo = std::fs::read_to_string(&geo_path).is_ok_and(|g| g == geo);
    if same_geo && msh_path.exists() {
        return Ok(msh_path);
    }
    std::fs::write(&geo_path, &geo).map_err(|e| io_err(&geo_path, e))?;
    eprintln!("[bench] gmsh: meshing {}", geo_path.display());
    let tmp = msh_path.with_extension("msh.part");
    let status = Command::new("gmsh")
        .args(["-3", "-nt", "1", "-format", "msh41", "-v", "2"])
        .arg(&geo_path)
        .arg("-o")
        .arg(&tmp)
        .stdout(Stdio::null())
        .status()
        .map_err(|e| io_err(Path::new("gmsh"), e))?;
    if !status.success() {
        return Err(io_err(&geo_path, format!("gmsh failed: {status}")));
    }
    std::fs::rename(&tmp, &msh_path).map_err(|e| io_err(&msh_path, e))?;
    Ok(msh_path)
}

/// The table line of a row.
pub fn format_row(r: &Mesh3Row) -> String {
    let total = r.read_s + r.build_s;
    format!(
        "{:>9} {:>9} {:>8} {:>8.3} {:>8.3} {:>8.3} {:>9.2} {:>9.2} {:>8.1}",
        r.cells,
        r.faces,
        r.vertices,
        r.read_s,
        r.build_s,
        total,
        1e6 * r.read_s / r.cells as f64,
        1e6 * r.build_s / r.cells as f64,
        r.peak_mib
    )
}

/// The header of [`format_row`]'s table.
pub const HEADER: &str = "    cells     faces vertices   read_s  build_s  total_s read_us/K \
                          build_us/K peak_MiB";

/// `--mesh3d`: every target up to `max_cells`, each in a child process of `exe`, printed on
/// stdout as it is known; meshes in `mesh_dir`.
pub fn run(exe: &Path, mesh_dir: &Path, max_cells: usize) -> gradvi::Result<()> {
    println!("{HEADER}");
    for &n in TARGETS.iter().filter(|&&n| n <= max_cells) {
        let file = cube_mesh(mesh_dir, n)?;
        let mut cmd = Command::new(exe);
        cmd.arg("bench").arg("--mesh3d-child").arg(&file);
        let out = stdout_of(cmd, exe, &format!("mesh3d case {}", file.display()))?;
        let row: Mesh3Row = serde_json::from_str(out.trim())
            .map_err(|e| bad(format!("mesh3d case {}: {e}", file.display())))?;
        println!("{}", format_row(&row));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_mesh_is_read_built_and_printed() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let file = root.join("tests/data/mesh3d/cube6_41.msh");
        let r = run_one(&file).unwrap();
        assert_eq!((r.cells, r.vertices), (6, 8));
        // 6 tetrahedra of a cube: 12 boundary triangles and 6 interior ones
        assert_eq!(r.faces, 18);
        assert!(r.read_s >= 0.0 && r.build_s >= 0.0 && r.peak_mib > 0.0);
        let line = format_row(&r);
        assert_eq!(
            line.split_whitespace().count(),
            HEADER.split_whitespace().count()
        );
        assert!(line.trim_start().starts_with("6 "));
    }

    #[test]
    fn mesh_sizes_follow_the_inverse_cube_law() {
        assert!((mesh_size(1_014_275) - 0.0166).abs() < 1e-15);
        // 1 014 275 / 8 rounds down by 3/8 of a cell: the size grows by about 10⁻⁶ of itself
        assert!((mesh_size(1_014_275 / 8) - 0.0332).abs() < 1e-7);
    }
}
