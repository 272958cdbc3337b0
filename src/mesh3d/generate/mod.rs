//! Deterministic 3D mesh generators: families of meshes of a box indexed by a level, built as
//! a [`Polyhedra`] with flat arrays filled in parallel and no per-cell allocation.
//!
//! | family | name | cells of level k (n = 2^(k+1) cubes per side) | largest level |
//! |---|---|---|---|
//! | [`Family3::Cubes`] ([`cubes()`]) | `cubes` | n³ cubes | 7 (256³, 16.8 M cells) |
//! | [`Family3::Kuhn`] ([`kuhn()`]) | `kuhn` (or `tetrahedra`) | 6n³ tetrahedra, 6 per cube around its main diagonal | 6 (12.6 M) |
//! | [`Family3::Prisms`] ([`prisms()`]) | `prisms` | 2n³ triangular prisms, 2 per cube | 7 (33.6 M) |
//! | [`Family3::Refined`] ([`refined()`]) | `refined` | 9n³/2: a checkerboard of the n³ cubes split into 8, the others polyhedra with up to 24 faces | 6 (9.4 M) |
//! | [`Family3::Warped`] ([`warped()`]) | `warped` | n³ hexahedra, interior points moved at random (seed [`warped::SEED`]), faces not planar | 7 (16.8 M) |
//!
//! Level k has n = 2^(k+1) cubes per side, as the 2D Cartesian family (level 1: 4³ cubes). The
//! largest levels come from the cap [`MAX_CELLS`] = 2^26 cells shared with the 2D generators.
//! Each construction, its numbering and its exact counts are documented in its module
//! ([`cubes`](mod@cubes), [`kuhn`](mod@kuhn), [`prisms`](mod@prisms),
//! [`refined`](mod@refined), [`warped`](mod@warped)); the grid they start from in
//! [`grid`]. Every face is listed by each of its cells, counter-clockwise seen from outside
//! that cell. As the 2D generators, the generators tag neither cells nor boundary faces.
//!
//! The generators never panic on their arguments: a level out of range, an odd n for the
//! refined family or a domain that is not a finite box ([`Cuboid::is_proper`]) give
//! [`Error::InvalidData`]; before allocating anything, the memory the mesh needs is estimated
//! from its exact counts ([`Family3::polyhedra_estimate`]) and a request beyond the caller's
//! [`MemoryBudget`] gives [`MeshError::TooLarge`](crate::MeshError::TooLarge) with the estimate.
//! [`Family3::polyhedra`] gives the description of a level on a box, [`Family3::generate`] and
//! [`Family3::generate_on`] the validated [`PolyMesh3`] built from it (its memory estimate,
//! [`Family3::memory_estimate`], includes the build's).

pub mod cubes;
mod fill;
pub mod grid;
pub mod kuhn;
pub mod prisms;
pub mod refined;
mod split;
pub mod warped;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_mesh;

pub use crate::mesh::generate::MAX_CELLS;
pub use cubes::cubes;
pub use kuhn::kuhn;
pub use prisms::prisms;
pub use refined::refined;
pub use warped::warped;

use crate::budget::MemoryBudget;
use crate::error::{Error, Result};
use crate::mesh3d::{Cuboid, PolyMesh3, Polyhedra, boundary_surface_bytes, mesh3_bytes};
use std::fmt;
use std::str::FromStr;

/// Cells, face sides, face vertices and vertices of a generated mesh; `None` if they overflow.
pub(crate) type Counts3 = Option<[u64; 4]>;

/// The bytes of a [`Polyhedra`] with these counts: 24 per vertex, 4 per entry of `cell_ptr`,
/// `face_ptr` and `face_vertices`; `u64::MAX` if they overflow.
pub(crate) fn polyhedra_bytes(counts: Counts3) -> u64 {
    counts.map_or(u64::MAX, |[c, s, v, p]| {
        p.saturating_mul(24)
            .saturating_add(c.saturating_add(s).saturating_add(2).saturating_mul(4))
            .saturating_add(v.saturating_mul(4))
    })
}

/// `Ok` if a generator may build `what` with n ≥ 1 cubes per side on `domain`, whose counts
/// are `counts`, needing `extra` bytes besides the description: n ≥ 1, a finite box, at most
/// [`MAX_CELLS`] cells and 32-bit offsets ([`Error::InvalidData`] otherwise), and the
/// description plus `extra` within `budget` ([`MeshError::TooLarge`](crate::MeshError::TooLarge)).
pub(crate) fn check_request(
    what: &str,
    n: usize,
    domain: Cuboid,
    counts: Counts3,
    extra: u64,
    budget: MemoryBudget,
) -> Result<()> {
    if n == 0 {
        return Err(Error::InvalidData(format!(
            "{what}: a 3D grid needs at least one cube per side"
        )));
    }
    check_domain(domain)?;
    let Some(c) = counts else {
        return Err(Error::InvalidData(format!(
            "{what} would have more cells than can be counted (limit {MAX_CELLS})"
        )));
    };
    if c[0] > MAX_CELLS as u64 {
        return Err(Error::InvalidData(format!(
            "{what} would have {} cells, more than the limit of {MAX_CELLS}",
            c[0]
        )));
    }
    if c.iter().any(|&x| x >= u64::from(u32::MAX)) {
        return Err(Error::InvalidData(format!(
            "{what} would have more face vertices or points than 32-bit ids number"
        )));
    }
    let bytes = polyhedra_bytes(counts).saturating_add(extra);
    budget.check(what, bytes).map_err(Error::from)
}

/// `Ok` if `domain` is a finite box with x0 < x1, y0 < y1 and z0 < z1.
fn check_domain(domain: Cuboid) -> Result<()> {
    if domain.is_proper() {
        Ok(())
    } else {
        Err(Error::InvalidData(format!(
            "the domain {domain} is not a finite box with x0 < x1, y0 < y1, z0 < z1"
        )))
    }
}

/// A family of generated 3D meshes, indexed by a level ≥ 1 with n = 2^(level+1) cubes per side
/// (see the table in the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Family3 {
    /// n³ cubes ([`cubes()`]).
    Cubes,
    /// 6n³ Kuhn tetrahedra ([`kuhn()`]).
    Kuhn,
    /// 2n³ triangular prisms ([`prisms()`]).
    Prisms,
    /// n³ cubes, the checkerboard (i + j + k even) split into 8 ([`refined()`]).
    Refined,
    /// n³ randomly perturbed hexahedra with the seed [`warped::SEED`] ([`warped()`]).
    Warped,
}

impl Family3 {
    /// The five families, in this order: Cubes, Kuhn, Prisms, Refined, Warped.
    pub const ALL: [Family3; 5] = [
        Family3::Cubes,
        Family3::Kuhn,
        Family3::Prisms,
        Family3::Refined,
        Family3::Warped,
    ];

    /// The lowercase name accepted by [`Family3::from_str`].
    pub fn name(self) -> &'static str {
        match self {
            Family3::Cubes => "cubes",
            Family3::Kuhn => "kuhn",
            Family3::Prisms => "prisms",
            Family3::Refined => "refined",
            Family3::Warped => "warped",
        }
    }

    /// Number of cells of the mesh at `level`, computed without building it; saturates at
    /// `usize::MAX` for absurd levels, and is 0 for level 0 (which is rejected).
    pub fn cells_at_level(self, level: usize) -> usize {
        if level == 0 {
            return 0;
        }
        self.counts(level)
            .and_then(|c| usize::try_from(c[0]).ok())
            .unwrap_or(usize::MAX)
    }

    /// Cells, face sides, face vertices and vertices of the mesh at `level`.
    fn counts(self, level: usize) -> Counts3 {
        let n = level_n(level)?;
        match self {
            Family3::Cubes | Family3::Warped => split::counts(n, cubes::CUBE),
            Family3::Kuhn => split::counts(n, kuhn::KUHN),
            Family3::Prisms => split::counts(n, prisms::PRISMS),
            Family3::Refined => refined::counts(n),
        }
    }

    /// The largest level whose mesh has at most [`MAX_CELLS`] cells (Cubes 7, Kuhn 6,
    /// Prisms 7, Refined 6, Warped 7).
    pub fn max_level(self) -> usize {
        let mut level = 1;
        while self
            .counts(level + 1)
            .is_some_and(|c| c[0] <= MAX_CELLS as u64)
        {
            level += 1;
        }
        level
    }

    /// `Ok` if `level` is between 1 and [`Family3::max_level`], else [`Error::InvalidData`]
    /// naming the family, the level and its number of cells.
    pub fn check_level(self, level: usize) -> Result<()> {
        let max = self.max_level();
        if level == 0 || level > max {
            let cells = match self.counts(level) {
                Some(c) if level > 0 => format!(" ({} cells)", c[0]),
                _ if level > 0 => " (too many cells to count)".to_string(),
                _ => String::new(),
            };
            return Err(Error::InvalidData(format!(
                "3D {} mesh level {level}{cells} is invalid: levels go from 1 to {max} \
                 (at most {MAX_CELLS} cells)",
                self.name()
            )));
        }
        Ok(())
    }

    /// Estimated peak memory, in bytes, of [`Family3::polyhedra`] at `level`: the description
    /// (and, for the refined family, its table of fine points); `u64::MAX` when it cannot be
    /// counted.
    pub fn polyhedra_estimate(self, level: usize) -> u64 {
        let extra = match (self, level_n(level)) {
            (Family3::Refined, Some(n)) => refined::table_bytes(n),
            _ => 0,
        };
        polyhedra_bytes(self.counts(level)).saturating_add(extra)
    }

    /// The description of this family's mesh at `level` on `domain` (the unit cube:
    /// [`Cuboid::UNIT`]). [`Error::InvalidData`] for a domain that is not a finite box or a
    /// level out of 1 ..= [`Family3::max_level`];
    /// [`MeshError::TooLarge`](crate::MeshError::TooLarge) (with the estimate) if
    /// [`Family3::polyhedra_estimate`] exceeds `budget`, before anything is allocated.
    pub fn polyhedra(
        self,
        level: usize,
        domain: Cuboid,
        budget: MemoryBudget,
    ) -> Result<Polyhedra> {
        check_domain(domain)?;
        self.check_level(level)?;
        let what = format!(
            "the 3D {} mesh of level {level} ({} cells)",
            self.name(),
            self.cells_at_level(level)
        );
        budget
            .check(what, self.polyhedra_estimate(level))
            .map_err(Error::from)?;
        let n = level_n(level).expect("checked by check_level");
        match self {
            Family3::Cubes => cubes(n, domain, budget),
            Family3::Kuhn => kuhn(n, domain, budget),
            Family3::Prisms => prisms(n, domain, budget),
            Family3::Refined => refined(n, domain, budget),
            Family3::Warped => warped(n, domain, warped::SEED, budget),
        }
    }
}

impl Family3 {
    /// Estimated peak memory, in bytes, of [`Family3::generate`] at `level`: the description
    /// ([`Family3::polyhedra_estimate`]) plus what building the mesh from it needs
    /// ([`mesh3_bytes`], and [`boundary_surface_bytes`] for the boundary loop entries, at most
    /// those of the boundary cubes of the n³ grid: 6n² of the n³ cubes, so a fraction 6/n of
    /// all loop entries); `u64::MAX` when it cannot be counted.
    pub fn memory_estimate(self, level: usize) -> u64 {
        let build = self
            .counts(level)
            .zip(level_n(level))
            .map_or(u64::MAX, |([c, s, v, p], n)| {
                let boundary = v.saturating_mul(6) / n.max(6) as u64;
                mesh3_bytes(c, s, v, p).saturating_add(boundary_surface_bytes(boundary, p))
            });
        self.polyhedra_estimate(level).saturating_add(build)
    }

    /// The validated mesh of this family at `level` on the unit cube
    /// ([`Family3::generate_on`] with [`Cuboid::UNIT`]).
    pub fn generate(self, level: usize, budget: MemoryBudget) -> Result<PolyMesh3> {
        self.generate_on(level, Cuboid::UNIT, budget)
    }

    /// The validated mesh of this family at `level` on `domain`: [`Family3::polyhedra`] built
    /// by [`PolyMesh3::from_polyhedra`]. Errors as [`Family3::polyhedra`], with the whole
    /// [`Family3::memory_estimate`] checked against `budget` before anything is allocated; the
    /// build is given what the description leaves of the budget.
    pub fn generate_on(
        self,
        level: usize,
        domain: Cuboid,
        budget: MemoryBudget,
    ) -> Result<PolyMesh3> {
        check_domain(domain)?;
        self.check_level(level)?;
        let what = format!(
            "the 3D {} mesh of level {level} ({} cells)",
            self.name(),
            self.cells_at_level(level)
        );
        budget
            .check(what, self.memory_estimate(level))
            .map_err(Error::from)?;
        let p = self.polyhedra(level, domain, budget)?;
        let held = polyhedra_bytes(self.counts(level));
        let rest = MemoryBudget::new(budget.bytes().saturating_sub(held));
        Ok(PolyMesh3::from_polyhedra(p, rest)?)
    }
}

/// n = 2^(level+1), or `None` on overflow.
fn level_n(level: usize) -> Option<usize> {
    let shift = u32::try_from(level.checked_add(1)?).ok()?;
    1usize.checked_shl(shift)
}

impl fmt::Display for Family3 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Family3 {
    type Err = Error;

    /// Parses `"cubes"`, `"kuhn"` (or `"tetrahedra"`), `"prisms"`, `"refined"` or `"warped"`
    /// (case-insensitive, surrounding blanks ignored); the error for any other name lists the
    /// families.
    fn from_str(s: &str) -> Result<Self> {
        let t = s.trim();
        if t.eq_ignore_ascii_case("tetrahedra") {
            return Ok(Family3::Kuhn);
        }
        Family3::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(t))
            .ok_or_else(|| {
                Error::InvalidData(format!(
                    "unknown 3D mesh family {s:?}: expected one of \"cubes\", \"kuhn\" (or \
                     \"tetrahedra\"), \"prisms\", \"refined\" or \"warped\""
                ))
            })
    }
}
