//! Deterministic mesh generators: no file is ever needed.
//!
//! | generator | cells | reproduces |
//! |---|---|---|
//! | [`cartesian()`], [`cartesian_rect`] | nx × ny rectangles | FVCA5 `mesh2_k` (level k = 2^(k+1) squares per side), `cartNxN` |
//! | [`cartesian_triangles`] | 2·nx·ny triangles (each square cut by its diagonal (i,j)–(i+1,j+1)) | the grid of PETSc's `snes/tutorials/ex9.c` (P1 = five-point Laplacian) |
//! | [`hexagonal()`] (level ≥ 1), [`hexagonal_grid`] (any n) | (n+1)² mostly hexagonal cells, n = 10·2^(level−1) | HArDCore2D / FVCA5 `hexa1_1` … `hexa1_5` exactly (same vertices in the same order, same cells) |
//! | [`kershaw()`] (level ≥ 1) | (17·level)² quadrangles | FVCA5 `mesh4_1_1` … `mesh4_1_6` (Kershaw meshes), vertices in the same order to 6e-11 |
//!
//! The maths of each construction is documented in its module ([`cartesian`](mod@cartesian),
//! [`hexagonal`](mod@hexagonal), [`kershaw`](mod@kershaw)). All generators return a validated
//! [`PolyMesh`] (counter-clockwise cells) and never panic: invalid arguments, and meshes larger
//! than [`MAX_CELLS`], are reported as [`Error::InvalidData`]. Before allocating anything, every
//! generator estimates the memory it will need ([`mesh_bytes`], from the exact numbers of
//! cells, vertices and edges) and refuses, with [`MeshError::TooLarge`](crate::MeshError::TooLarge)
//! giving the estimate, a mesh that does not fit in the memory budget. The budget is the
//! caller's ([`MemoryBudget`]): [`Family::generate`], [`Family::generate_on`] and the `_within`
//! generators take it; [`cartesian()`], [`cartesian_rect`], [`cartesian_triangles`],
//! [`hexagonal()`], [`hexagonal_grid`] and [`kershaw()`] use the fixed
//! [`MemoryBudget::DEFAULT`] (8 GiB), so that their answer does not depend on the machine.
//!
//! [`Family`] names the four families for the command line (`"cartesian"`, `"hexagonal"`,
//! `"kershaw"`, `"triangles"`), generates a level ([`Family::generate`]) and predicts its size
//! without building it ([`Family::cells_at_level`]). Levels per family:
//!
//! | family | level k | cells | largest level |
//! |---|---|---|---|
//! | Cartesian | n = 2^(k+1) squares per side (like FVCA5 `mesh2_k`: level 1 = 4×4, level 5 = 64×64) | 4^(k+1) | 12 (8192², 67 M cells) |
//! | Hexagonal | `hexa1_k`: n = 10·2^(k−1) lattice steps per side, 20·2^(k−1) edges on x=0 | (n+1)² (121, 441, 1681, …) | 10 (26.2 M cells) |
//! | Kershaw | `mesh4_1_k`: 17k × 17k quadrangles, 17k edges on x=0 | 289 k² | 481 (66.9 M cells) |
//! | Triangles | the Cartesian grid of level k, each square cut by its diagonal from lower left to upper right ([`cartesian_triangles`]) | 2·4^(k+1) | 11 (2·4096², 33.6 M cells: PETSc ex9's 4097² grid) |
//!
//! The largest levels come from the cap [`MAX_CELLS`] = 2^26 cells; the memory budget stops
//! earlier unless it is large. Estimated peaks ([`Family::memory_estimate`]): Cartesian level 9
//! (1 M cells) 0.4 GB, level 10 1.5 GB, level 11 6.0 GB; hexagonal level 8 (1.6 M cells) 0.9 GB,
//! level 9 3.7 GB; Kershaw level 100 (2.9 M cells) 1.0 GB, level 240 5.9 GB; triangles level 9
//! (2.1 M cells) 0.5 GB, level 10 2.1 GB, level 11 8.5 GB (1 GB = 10⁹ bytes). How these
//! estimates compare with measured peaks is in `replication/BENCHMARKS.md` ("Measurements behind
//! the defaults").

pub mod cartesian;
pub mod hexagonal;
pub mod kershaw;

pub use cartesian::{
    cartesian, cartesian_rect, cartesian_rect_within, cartesian_triangles,
    cartesian_triangles_within,
};
pub use hexagonal::{hexagonal, hexagonal_grid, hexagonal_grid_within};
pub use kershaw::{kershaw, kershaw_within};

use crate::budget::{MemoryBudget, mesh_bytes, try_vec};
use crate::error::{Error, Result};
use crate::mesh::{Overlap, PolyMesh, Rect};
use std::fmt;
use std::str::FromStr;

/// Largest number of cells any generator builds (2^26 ≈ 67 million); beyond this the
/// generators return [`Error::InvalidData`] instead of exhausting memory.
pub const MAX_CELLS: usize = 1 << 26;

/// Checks a requested cell count against [`MAX_CELLS`] (`None` means the count overflowed).
pub(crate) fn check_cell_count(what: &str, cells: Option<usize>) -> Result<()> {
    match cells {
        Some(c) if c <= MAX_CELLS => Ok(()),
        Some(c) => Err(Error::InvalidData(format!(
            "{what} would have {c} cells, more than the limit of {MAX_CELLS}"
        ))),
        None => Err(Error::InvalidData(format!(
            "{what} would have more cells than can be counted (limit {MAX_CELLS})"
        ))),
    }
}

/// Numbers of cells, cell sides (entries of the cell vertex lists), vertices and edges of a
/// mesh, for its memory estimate; `None` if they overflow.
pub(crate) type Counts = Option<[u64; 4]>;

/// [`MeshError::TooLarge`](crate::MeshError::TooLarge) (as an [`Error`]) if a mesh with these counts would need more memory
/// than `budget`.
pub(crate) fn check_memory(what: &str, counts: Counts, budget: MemoryBudget) -> Result<()> {
    let bytes = counts.map_or(u64::MAX, |[c, s, v, e]| mesh_bytes(c, s, v, e));
    budget.check(what, bytes).map_err(Error::from)
}

/// A family of generated meshes, indexed by a refinement level ≥ 1 (see the module docs for
/// what a level means in each family).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Family {
    /// Uniform squares on \[0,1\]²; level k has 2^(k+1) × 2^(k+1) cells (FVCA5 `mesh2_k`).
    Cartesian,
    /// Smoothly distorted hexagons on \[0,1\]²; level k reproduces `hexa1_k`.
    Hexagonal,
    /// Kershaw quadrangles on \[0,1\]²; level k reproduces `mesh4_1_k` (17k × 17k cells).
    Kershaw,
    /// The Cartesian grid of level k on \[0,1\]² with every square cut into two triangles by
    /// its diagonal (i,j)–(i+1,j+1) ([`cartesian_triangles`]): 2 · 2^(k+1) × 2^(k+1) cells, the
    /// triangle mesh the P1 scheme needs.
    Triangles,
}

impl Family {
    /// The four families, in this order: Cartesian, Hexagonal, Kershaw, Triangles.
    pub const ALL: [Family; 4] = [
        Family::Cartesian,
        Family::Hexagonal,
        Family::Kershaw,
        Family::Triangles,
    ];

    /// The lowercase name accepted by [`Family::from_str`].
    pub fn name(self) -> &'static str {
        match self {
            Family::Cartesian => "cartesian",
            Family::Hexagonal => "hexagonal",
            Family::Kershaw => "kershaw",
            Family::Triangles => "triangles",
        }
    }

    /// Number of cells of the mesh at `level`, computed without building it; saturates at
    /// `usize::MAX` for absurd levels, and is 0 for level 0 (which [`Family::generate`] rejects).
    pub fn cells_at_level(self, level: usize) -> usize {
        if level == 0 {
            return 0;
        }
        self.checked_cells(level).unwrap_or(usize::MAX)
    }

    fn checked_cells(self, level: usize) -> Option<usize> {
        match self {
            Family::Cartesian => {
                let n = cartesian_level_n(level)?;
                n.checked_mul(n)
            }
            Family::Hexagonal => {
                let n = hexagonal::level_n(level)?.checked_add(1)?;
                n.checked_mul(n)
            }
            Family::Kershaw => {
                let n = level.checked_mul(kershaw::COARSE_N)?;
                n.checked_mul(n)
            }
            Family::Triangles => {
                let n = cartesian_level_n(level)?;
                n.checked_mul(n)?.checked_mul(2)
            }
        }
    }

    /// The largest level whose mesh has at most [`MAX_CELLS`] cells
    /// (Cartesian 11, Hexagonal 9, Kershaw 240, Triangles 10).
    pub fn max_level(self) -> usize {
        let mut level = 1;
        while self
            .checked_cells(level + 1)
            .is_some_and(|c| c <= MAX_CELLS)
        {
            level += 1;
        }
        level
    }

    /// `Ok` if `level` is between 1 and [`Family::max_level`], else [`Error::InvalidData`]
    /// saying which levels are valid.
    pub fn check_level(self, level: usize) -> Result<()> {
        let max = self.max_level();
        if level == 0 || level > max {
            let cells = match self.checked_cells(level) {
                Some(c) if level > 0 => format!(" ({c} cells)"),
                _ if level > 0 => " (too many cells to count)".to_string(),
                _ => String::new(),
            };
            return Err(Error::InvalidData(format!(
                "{} mesh level {level}{cells} is invalid: levels go from 1 to {max} \
                 (at most {MAX_CELLS} cells)",
                self.name()
            )));
        }
        Ok(())
    }

    /// The counts of the mesh at `level` (cells, cell sides, vertices, edges).
    fn counts(self, level: usize) -> Counts {
        match self {
            Family::Cartesian => {
                let n = cartesian_level_n(level)?;
                cartesian::counts(n, n)
            }
            Family::Hexagonal => hexagonal::counts(hexagonal::level_n(level)?),
            Family::Kershaw => kershaw::counts(level),
            Family::Triangles => {
                let n = cartesian_level_n(level)?;
                cartesian::triangle_counts(n, n)
            }
        }
    }

    /// Estimated peak memory, in bytes, of generating the mesh at `level`
    /// ([`mesh_bytes`]); `u64::MAX` when it cannot be counted.
    pub fn memory_estimate(self, level: usize) -> u64 {
        self.counts(level)
            .map_or(u64::MAX, |[c, s, v, e]| mesh_bytes(c, s, v, e))
    }

    /// Builds the mesh of this family at `level` (see the table in the module docs).
    /// Level 0 and levels above [`Family::max_level`] give [`Error::InvalidData`]; a mesh whose
    /// [`Family::memory_estimate`] exceeds `budget` gives
    /// [`MeshError::TooLarge`](crate::MeshError::TooLarge) (with the estimate), before anything
    /// is allocated.
    pub fn generate(self, level: usize, budget: MemoryBudget) -> Result<PolyMesh> {
        self.check_level(level)?;
        let what = format!(
            "the {} mesh of level {level} ({} cells)",
            self.name(),
            self.cells_at_level(level)
        );
        check_memory(&what, self.counts(level), budget)?;
        match self {
            Family::Cartesian => {
                let n = cartesian_level_n(level).expect("checked by check_level");
                cartesian_rect_within(n, n, [0.0, 1.0], [0.0, 1.0], budget)
            }
            Family::Hexagonal => {
                let n = hexagonal::level_n(level).expect("checked by check_level");
                hexagonal_grid_within(n, budget)
            }
            Family::Kershaw => kershaw_within(level, budget),
            Family::Triangles => {
                let n = cartesian_level_n(level).expect("checked by check_level");
                cartesian_triangles_within(n, n, [0.0, 1.0], [0.0, 1.0], budget)
            }
        }
    }

    /// The mesh of this family at `level` on the rectangle `domain` instead of the unit square.
    /// The Cartesian and triangle families are generated on the rectangle directly
    /// ([`cartesian_rect_within`], [`cartesian_triangles_within`]: one build, one validation,
    /// the last grid line exactly on x1 and y1); the others are built on the unit square and
    /// mapped ([`map_unit_square`]). Errors as [`Family::generate`], and
    /// [`Error::InvalidData`] for a domain that is not a finite rectangle.
    pub fn generate_on(self, level: usize, domain: Rect, budget: MemoryBudget) -> Result<PolyMesh> {
        check_domain(domain)?;
        match self {
            Family::Cartesian | Family::Triangles => {
                self.check_level(level)?;
                let n = cartesian_level_n(level).expect("checked by check_level");
                if self == Family::Cartesian {
                    cartesian_rect_within(n, n, domain.x, domain.y, budget)
                } else {
                    cartesian_triangles_within(n, n, domain.x, domain.y, budget)
                }
            }
            Family::Hexagonal | Family::Kershaw => {
                map_unit_square(&self.generate(level, budget)?, domain)
            }
        }
    }
}

/// `Ok` if `domain` is a finite rectangle with x0 < x1 and y0 < y1 ([`Rect::is_proper`]).
fn check_domain(domain: Rect) -> Result<()> {
    if domain.is_proper() {
        Ok(())
    } else {
        Err(Error::InvalidData(format!(
            "the domain {domain} is not a finite rectangle with x0 < x1, y0 < y1"
        )))
    }
}

/// The mesh `m` of the unit square mapped onto `domain` = \[x0, x1\] × \[y0, y1\] by
/// (x, y) ↦ (x0 + (x1 − x0) x, y0 + (y1 − y0) y), validated again (rounding could in
/// principle spoil a nearly degenerate cell). Boundary tags are not kept.
pub fn map_unit_square(m: &PolyMesh, domain: Rect) -> Result<PolyMesh> {
    check_domain(domain)?;
    let ([x0, x1], [y0, y1]) = (domain.x, domain.y);
    let v = m
        .vertices()
        .iter()
        .map(|p| [x0 + (x1 - x0) * p[0], y0 + (y1 - y0) * p[1]])
        .collect();
    let mut cell_ptr = try_vec(m.n_cells() + 1, "the cell offsets")?;
    cell_ptr.push(0);
    let sides = (0..m.n_cells()).map(|k| m.cell_vertices(k).len()).sum();
    let mut cell_verts: Vec<usize> = try_vec(sides, "the vertices of the cells")?;
    for k in 0..m.n_cells() {
        cell_verts.extend(m.cell_vertices(k).iter().map(|&v| v as usize));
        cell_ptr.push(cell_verts.len());
    }
    Ok(PolyMesh::from_flat_cells(
        v,
        cell_ptr,
        cell_verts,
        Overlap::Sweep,
    )?)
}

/// n = 2^(level+1), or `None` on overflow.
fn cartesian_level_n(level: usize) -> Option<usize> {
    let shift = u32::try_from(level.checked_add(1)?).ok()?;
    1usize.checked_shl(shift)
}

/// The names of [`Family::ALL`], quoted, for messages: `"cartesian", "hexagonal", "kershaw"
/// or "triangles"`.
fn family_list() -> String {
    let names: Vec<String> = Family::ALL
        .iter()
        .map(|f| format!("{:?}", f.name()))
        .collect();
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => names.concat(),
    }
}

impl fmt::Display for Family {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Family {
    type Err = Error;

    /// Parses `"cartesian"`, `"hexagonal"`, `"kershaw"` or `"triangles"` (case-insensitive,
    /// surrounding blanks ignored); the error for any other name lists the families.
    fn from_str(s: &str) -> Result<Self> {
        let t = s.trim();
        Family::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(t))
            .ok_or_else(|| {
                Error::InvalidData(format!(
                    "unknown mesh family {s:?}: expected one of {}",
                    family_list()
                ))
            })
    }
}

/// The total area of the cells (for the generators' tests).
#[cfg(test)]
pub(crate) fn total_area(m: &PolyMesh) -> f64 {
    (0..m.n_cells()).map(|k| m.measure(k)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn family_names_round_trip() {
        for f in Family::ALL {
            assert_eq!(f.name().parse::<Family>().unwrap(), f);
            assert_eq!(f.to_string(), f.name());
        }
        assert_eq!(" Kershaw ".parse::<Family>().unwrap(), Family::Kershaw);
        assert_eq!("TRIANGLES".parse::<Family>().unwrap(), Family::Triangles);
        assert_eq!(Family::Triangles.name(), "triangles");
        let e = "hexa".parse::<Family>().unwrap_err();
        assert!(
            matches!(e, Error::InvalidData(ref m) if m.contains("hexagonal")),
            "{e}"
        );
    }

    #[test]
    fn an_unknown_family_lists_all_four() {
        match "octagonal".parse::<Family>() {
            Err(Error::InvalidData(m)) => {
                assert_eq!(
                    m,
                    "unknown mesh family \"octagonal\": expected one of \"cartesian\", \
                     \"hexagonal\", \"kershaw\" or \"triangles\""
                );
                for f in Family::ALL {
                    assert!(m.contains(&format!("\"{f}\"")), "{m}");
                }
            }
            r => panic!("{r:?}"),
        }
    }

    #[test]
    fn generated_on_a_rectangle_is_the_unit_square_mesh_mapped() {
        let d = Rect::new([-2.0, 2.0], [-1.0, 0.5]);
        for f in Family::ALL {
            let unit = f.generate(2, MemoryBudget::DEFAULT).unwrap();
            let mapped = map_unit_square(&unit, d).unwrap();
            let on = f.generate_on(2, d, MemoryBudget::DEFAULT).unwrap();
            // the rectangle asked for is the rectangle the mesh covers
            assert_eq!(on.bounding_box(), d, "{f}");
            assert_eq!(unit.bounding_box(), Rect::UNIT, "{f}");
            assert_eq!(on.n_cells(), unit.n_cells(), "{f}");
            for k in 0..on.n_cells() {
                assert_eq!(on.cell_vertices(k), mapped.cell_vertices(k), "{f} cell {k}");
            }
            for (p, q) in on.vertices().iter().zip(mapped.vertices()) {
                assert!(
                    (p[0] - q[0]).abs() <= 1e-15 && (p[1] - q[1]).abs() <= 1e-15,
                    "{f}"
                );
            }
            assert!((total_area(&on) - 6.0).abs() < 1e-12, "{f}");
            // the rectangle exactly: its corners are vertices
            let has = |x: f64, y: f64| on.vertices().iter().any(|p| p[0] == x && p[1] == y);
            assert!(has(-2.0, -1.0) && has(2.0, 0.5), "{f}");
        }
        for bad in [
            Rect::new([1.0, 0.0], [0.0, 1.0]),
            Rect::new([0.0, f64::NAN], [0.0, 1.0]),
            Rect::new([0.0, 1.0], [2.0, 2.0]),
        ] {
            for f in Family::ALL {
                let e = f
                    .generate_on(2, bad, MemoryBudget::DEFAULT)
                    .unwrap_err()
                    .to_string();
                assert!(e.contains("is not a finite rectangle"), "{f} {bad:?}: {e}");
            }
        }
        // the level is checked before anything is built
        let e = Family::Triangles
            .generate_on(12, d, MemoryBudget::DEFAULT)
            .unwrap_err()
            .to_string();
        assert!(e.contains("level 12"), "{e}");
        // and so is the budget, on a rectangle as on the unit square
        for f in Family::ALL {
            let small = MemoryBudget::new(f.memory_estimate(2) - 1);
            match f.generate_on(2, d, small) {
                Err(Error::InvalidMesh(crate::MeshError::TooLarge { .. })) => {}
                r => panic!("{f}: {r:?}"),
            }
        }
    }

    #[test]
    fn triangles_are_the_triangulated_cartesian_grid() {
        for level in 1..=4 {
            let m = Family::Triangles
                .generate(level, MemoryBudget::DEFAULT)
                .unwrap();
            let n = 1 << (level + 1);
            let reference = cartesian_triangles(n, n, [0.0, 1.0], [0.0, 1.0]).unwrap();
            assert!(m.is_triangular(), "level {level}");
            assert_eq!(m.vertices(), reference.vertices(), "level {level}");
            for k in 0..m.n_cells() {
                assert_eq!(m.cell_vertices(k), reference.cell_vertices(k));
            }
            // the same vertices as the Cartesian mesh of the same level, twice its cells
            let squares = Family::Cartesian
                .generate(level, MemoryBudget::DEFAULT)
                .unwrap();
            assert_eq!(m.vertices(), squares.vertices());
            assert_eq!(m.n_cells(), 2 * squares.n_cells());
            assert_eq!(m.n_edges(), squares.n_edges() + squares.n_cells());
            assert!((total_area(&m) - 1.0).abs() < 1e-12);
        }
        assert_eq!(Family::Triangles.cells_at_level(1), 32);
        assert_eq!(Family::Triangles.cells_at_level(4), 2 * 32 * 32);
        assert_eq!(Family::Triangles.cells_at_level(10), 2 * 2048 * 2048);
    }

    #[test]
    fn cells_at_level_matches_the_generated_meshes() {
        for f in Family::ALL {
            for level in 1..=2 {
                let m = f.generate(level, MemoryBudget::DEFAULT).unwrap();
                assert_eq!(m.n_cells(), f.cells_at_level(level), "{f} level {level}");
            }
        }
        assert_eq!(Family::Cartesian.cells_at_level(1), 16);
        assert_eq!(Family::Cartesian.cells_at_level(5), 64 * 64);
        assert_eq!(Family::Hexagonal.cells_at_level(4), 6561);
        assert_eq!(Family::Hexagonal.cells_at_level(5), 25921);
        assert_eq!(Family::Hexagonal.cells_at_level(7), 641 * 641);
        assert_eq!(Family::Kershaw.cells_at_level(6), 10404);
    }

    #[test]
    fn levels_are_validated_without_panicking() {
        assert_eq!(Family::Cartesian.max_level(), 12);
        assert_eq!(Family::Hexagonal.max_level(), 10);
        assert_eq!(Family::Kershaw.max_level(), 481);
        assert_eq!(Family::Triangles.max_level(), 11);
        for f in Family::ALL {
            let max = f.max_level();
            for level in [0, max + 1, max + 2, 64, 65, 1000, usize::MAX] {
                if level > 0 && level <= max {
                    continue;
                }
                match f.generate(level, MemoryBudget::DEFAULT) {
                    Err(Error::InvalidData(msg)) => assert!(msg.contains(f.name()), "{msg}"),
                    Err(e) => panic!("{f} level {level}: unexpected error {e}"),
                    Ok(_) => panic!("{f} level {level} was accepted"),
                }
                let _ = f.cells_at_level(level);
            }
            assert_eq!(f.cells_at_level(0), 0);
            assert!(f.cells_at_level(max) <= MAX_CELLS);
            assert!(f.cells_at_level(max + 1) > MAX_CELLS);
        }
        assert_eq!(Family::Cartesian.cells_at_level(usize::MAX), usize::MAX);
        assert_eq!(Family::Hexagonal.cells_at_level(200), usize::MAX);
        assert!(Family::Cartesian.check_level(12).is_ok());
        assert!(Family::Cartesian.check_level(13).is_err());
        assert!(Family::Hexagonal.check_level(11).is_err());
        assert!(Family::Kershaw.check_level(13).is_ok());
        assert!(Family::Triangles.check_level(11).is_ok());
        assert!(Family::Triangles.check_level(12).is_err());
    }

    #[test]
    fn counts_match_the_meshes_and_budgets_refuse_up_front() {
        let count = |m: &PolyMesh| {
            let sides: usize = (0..m.n_cells()).map(|k| m.cell_vertices(k).len()).sum();
            Some([m.n_cells(), sides, m.n_vertices(), m.n_edges()].map(|x| x as u64))
        };
        for f in Family::ALL {
            let levels = if f == Family::Triangles { 1..=4 } else { 1..=2 };
            for level in levels {
                assert_eq!(
                    f.counts(level),
                    count(&f.generate(level, MemoryBudget::DEFAULT).unwrap()),
                    "{f} {level}"
                );
            }
            let estimate = f.memory_estimate(2);
            assert!(f.generate(2, MemoryBudget::new(estimate)).is_ok());
            match f.generate(2, MemoryBudget::new(estimate - 1)) {
                Err(Error::InvalidMesh(crate::MeshError::TooLarge { bytes, budget, .. })) => {
                    assert_eq!((bytes, budget), (estimate, estimate - 1))
                }
                r => panic!("{f}: {r:?}"),
            }
            assert_eq!(f.memory_estimate(usize::MAX), u64::MAX);
        }
        for (nx, ny) in [(1, 1), (3, 5)] {
            assert_eq!(
                cartesian::counts(nx, ny),
                count(&cartesian(nx, ny).unwrap())
            );
            assert_eq!(
                cartesian::triangle_counts(nx, ny),
                count(&cartesian_triangles(nx, ny, [0.0, 1.0], [0.0, 1.0]).unwrap())
            );
        }
        for n in 1..5 {
            assert_eq!(hexagonal::counts(n), count(&hexagonal_grid(n).unwrap()));
        }
        let gb = |f: Family, l: usize| (f.memory_estimate(l) as f64 / 1e8).round() / 10.0;
        assert_eq!(
            [
                gb(Family::Cartesian, 9),
                gb(Family::Cartesian, 10),
                gb(Family::Cartesian, 11),
                gb(Family::Hexagonal, 8),
                gb(Family::Hexagonal, 9),
                gb(Family::Kershaw, 100),
                gb(Family::Kershaw, 240),
                gb(Family::Triangles, 9),
                gb(Family::Triangles, 10)
            ],
            [0.4, 1.5, 6.0, 0.9, 3.7, 1.0, 5.9, 0.5, 2.1]
        );
    }
}
