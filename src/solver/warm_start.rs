//! Warm starts of the monotony algorithm: an initial active set predicted by coarse solves.
//!
//! From A₀ = ∅ the monotony algorithm puts every violated unknown in the active set at once
//! and then frees one layer of cells along the free boundary per solve, so that NITER grows
//! like the number of cell layers between the first contact zone and the final one,
//! ∝ 1/h ∝ N^½ (`replication/BENCHMARKS.md` measures it). Every solve costs a numeric
//! factorisation, so the total grows like N^1.5.
//!
//! [`WarmStart::Nested`] bounds NITER instead: it solves the *same problem* (same A, f,
//! boundary conditions and barrier) with HMM on an nx × ny Cartesian mesh of the domain with
//! about N/16 cells (n ≈ √N / 4 per direction, at least 8), itself warm-started in the same
//! way from a mesh four times coarser per direction while that one has at least 16 cells per
//! direction, and starts the fine iteration from the predicted active set. A fine unknown is
//! predicted active where the coarse active indicator, interpolated bilinearly between the
//! centres of the four nearest coarse cells (linearly between the two nearest coarse faces
//! for a Signorini barrier), is at least [`THRESHOLD`] = 3/4: this erodes the coarse contact
//! zone a little, so that the fine iteration mostly *adds* unknowns, which it does in one
//! step, rather than freeing them, which it does one layer of cells per step.
//!
//! The warm start changes the path, never the answer: the stopping rule (A_{k+1} = A_k) and
//! the [`Certificate`](super::Certificate) do not depend on the start, so the solution is the
//! one of the cold iteration (the same discrete variational inequality has one solution); only
//! NITER and the time differ. NITER then counts the fine solves only; the coarse ones are
//! reported in [`WarmStartReport`].
//!
//! Requirements: the domain must fill its bounding box (a rectangle) — otherwise the
//! prediction is skipped with the reason in [`WarmStartReport::skipped`] and the iteration
//! starts cold. Boundary tags of the coarse edges are copied from the nearest fine boundary
//! edge, so boundary conditions given by gmsh tags carry over.

use crate::mesh::generate::cartesian_rect;
use crate::mesh::{Point, PolyMesh};
use crate::problem::{ConstraintKind, Problem};
use crate::scheme::Hmm;
use std::time::Instant;

/// How the monotony algorithm starts (`--warm-start cold|nested` on the command line).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum WarmStart {
    /// From A₀ = ∅ (the paper's algorithm; NITER comparable with its tables).
    #[default]
    Cold,
    /// From an active set predicted by nested coarse Cartesian HMM solves (see the module
    /// docs).
    Nested,
}

impl std::str::FromStr for WarmStart {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "cold" => Ok(WarmStart::Cold),
            "nested" => Ok(WarmStart::Nested),
            _ => Err(crate::Error::InvalidData(format!(
                "unknown warm start '{s}' (expected cold or nested)"
            ))),
        }
    }
}

impl std::fmt::Display for WarmStart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            WarmStart::Cold => "cold",
            WarmStart::Nested => "nested",
        })
    }
}

/// What a warm start did.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct WarmStartReport {
    /// The coarse meshes solved, finest first, as (nx, ny).
    pub levels: Vec<(usize, usize)>,
    /// Linear solves of all coarse levels.
    pub coarse_solves: usize,
    /// Size of the predicted active set on the fine unknowns.
    pub predicted_active: usize,
    /// Wall-clock time of the prediction, in seconds.
    pub seconds: f64,
    /// Why no prediction was made (the iteration then starts cold).
    pub skipped: Option<String>,
}

/// The active states of a coarse Cartesian solve, with the geometry to look them up.
struct Coarse {
    nx: usize,
    ny: usize,
    bbox: [f64; 4],
    /// Obstacle: active cells, row-major (j · nx + i).
    cells: Vec<bool>,
    /// Signorini: active boundary faces per side (bottom, right, top, left), indexed along
    /// the side in increasing coordinate.
    sides: [Vec<bool>; 4],
    /// Coarse linear solves of this level and the coarser ones.
    solves: usize,
    levels: Vec<(usize, usize)>,
}

/// A fine unknown is predicted active where the interpolated coarse active indicator is at
/// least this. 1 (all of the nearest coarse cells active) erodes the coarse contact zone by
/// half a coarse cell; 3/4 erodes it less and saved one or two fine solves in the benchmark's
/// Test 3 runs (1/2 and 1/4 cost more solves, since the fine iteration frees cells one layer
/// per solve but adds them all at once).
pub const THRESHOLD: f64 = 0.75;

/// Relative tolerance of the test "the domain fills its bounding box".
const RECTANGLE_TOL: f64 = 1e-9;

/// Predicts the active set of the constrained unknowns at `points` (in order) for `problem`
/// on `mesh` (the fine mesh). `Err(reason)` when no prediction can be made.
pub fn predict(
    mesh: &PolyMesh,
    problem: &Problem,
    points: &[Point],
) -> Result<(Vec<bool>, WarmStartReport), String> {
    let t0 = Instant::now();
    let constraint = problem
        .constraint
        .as_ref()
        .ok_or_else(|| "the problem has no barrier".to_string())?;
    let bbox = mesh.bounding_box();
    let (w, h) = (bbox[2] - bbox[0], bbox[3] - bbox[1]);
    let area: f64 = (0..mesh.n_cells()).map(|k| mesh.measure(k)).sum();
    if !((area - w * h).abs() <= RECTANGLE_TOL * w * h) {
        return Err(format!(
            "the nested warm start needs a rectangular domain; the mesh covers {area:.6e} of its bounding box's {:.6e}",
            w * h
        ));
    }
    let cells = mesh.n_cells() as f64 / 16.0;
    let nx = ((cells * w / h).sqrt().round() as usize).max(8);
    let ny = ((cells * h / w).sqrt().round() as usize).max(8);
    if 4 * nx * ny > mesh.n_cells() {
        return Err(format!(
            "the mesh ({} cells) is too coarse for a nested warm start",
            mesh.n_cells()
        ));
    }
    let tags = BoundaryTags::new(mesh);
    let coarse = Coarse::solve(nx, ny, bbox, problem, &tags)?;
    let predicted: Vec<bool> = points
        .iter()
        .map(|&p| match constraint.kind {
            ConstraintKind::Obstacle => coarse.predict_cell(p),
            ConstraintKind::Signorini => coarse.predict_face(p),
        })
        .collect();
    let report = WarmStartReport {
        levels: coarse.levels.clone(),
        coarse_solves: coarse.solves,
        predicted_active: predicted.iter().filter(|&&a| a).count(),
        seconds: t0.elapsed().as_secs_f64(),
        skipped: None,
    };
    Ok((predicted, report))
}

/// The fine boundary edges' midpoints and tags, to tag the coarse boundary edges.
struct BoundaryTags {
    points: Vec<(Point, i32)>,
}

impl BoundaryTags {
    fn new(mesh: &PolyMesh) -> Self {
        let points = mesh
            .boundary_edges()
            .iter()
            .map(|&e| (mesh.edge_midpoint(e), mesh.edge_tag(e)))
            .collect();
        BoundaryTags { points }
    }
    /// The tag of the fine boundary edge whose midpoint is nearest to `p`.
    fn nearest(&self, p: Point) -> i32 {
        let d2 = |q: Point| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
        self.points
            .iter()
            .min_by(|a, b| d2(a.0).total_cmp(&d2(b.0)))
            .map_or(0, |&(_, t)| t)
    }
}

impl Coarse {
    fn solve(
        nx: usize,
        ny: usize,
        bbox: [f64; 4],
        problem: &Problem,
        tags: &BoundaryTags,
    ) -> Result<Coarse, String> {
        let coarser = if nx.min(ny) / 4 >= 16 {
            Some(Coarse::solve(nx / 4, ny / 4, bbox, problem, tags)?)
        } else {
            None
        };
        let fail = |e: crate::Error| format!("coarse {nx} × {ny} solve: {e}");
        let mesh = cartesian_rect(nx, ny, [bbox[0], bbox[2]], [bbox[1], bbox[3]])
            .map_err(fail)?
            .with_boundary_tags(|p| tags.nearest(p));
        let scheme = Hmm::new(&mesh);
        let system = crate::assembly::DiscreteSystem::new(&scheme, problem, Default::default())
            .map_err(fail)?;
        let cons = super::constraints::build(&system, problem)
            .map_err(fail)?
            .ok_or_else(|| "the problem has no barrier".to_string())?;
        let kind = problem
            .constraint
            .as_ref()
            .map_or(ConstraintKind::Obstacle, |c| c.kind);
        let initial_active = coarser.as_ref().map(|c| {
            cons.dofs
                .iter()
                .map(|d| match kind {
                    ConstraintKind::Obstacle => c.predict_cell(d.point),
                    ConstraintKind::Signorini => c.predict_face(d.point),
                })
                .collect()
        });
        let opts = crate::vi::ActiveSetOptions {
            initial_active,
            ..Default::default()
        };
        let sol = crate::vi::active_set::solve(&system, &cons, &opts).map_err(fail)?;
        let mut out = Coarse {
            nx,
            ny,
            bbox,
            cells: vec![false; nx * ny],
            sides: [
                vec![false; nx],
                vec![false; ny],
                vec![false; nx],
                vec![false; ny],
            ],
            solves: sol.niter + coarser.as_ref().map_or(0, |c| c.solves),
            levels: vec![(nx, ny)],
        };
        if let Some(c) = coarser {
            out.levels.extend(c.levels);
        }
        for (d, &a) in cons.dofs.iter().zip(&sol.active) {
            if !a {
                continue;
            }
            match kind {
                ConstraintKind::Obstacle => {
                    let (i, j) = out.cell_of(d.point);
                    out.cells[j * nx + i] = true;
                }
                ConstraintKind::Signorini => {
                    let (side, i) = out.face_of(d.point);
                    out.sides[side][i] = true;
                }
            }
        }
        Ok(out)
    }

    /// Fractional grid coordinates of p.
    fn grid(&self, p: Point) -> (f64, f64) {
        let fx = (p[0] - self.bbox[0]) / (self.bbox[2] - self.bbox[0]);
        let fy = (p[1] - self.bbox[1]) / (self.bbox[3] - self.bbox[1]);
        (fx * self.nx as f64, fy * self.ny as f64)
    }

    /// The coarse cell holding p (clamped to the grid).
    fn cell_of(&self, p: Point) -> (usize, usize) {
        let (gx, gy) = self.grid(p);
        let i = (gx.floor().max(0.0) as usize).min(self.nx - 1);
        let j = (gy.floor().max(0.0) as usize).min(self.ny - 1);
        (i, j)
    }

    /// The side (bottom, right, top, left) nearest to the boundary point p and the index of
    /// the coarse face along it, with the fractional position along the side.
    fn side_of(&self, p: Point) -> (usize, f64) {
        let b = self.bbox;
        let dist = [p[1] - b[1], b[2] - p[0], b[3] - p[1], p[0] - b[0]];
        let side = (0..4)
            .min_by(|&a, &c| dist[a].abs().total_cmp(&dist[c].abs()))
            .unwrap_or(0);
        let (gx, gy) = self.grid(p);
        (side, if side % 2 == 0 { gx } else { gy })
    }

    fn face_of(&self, p: Point) -> (usize, usize) {
        let (side, g) = self.side_of(p);
        let n = self.sides[side].len();
        (side, (g.floor().max(0.0) as usize).min(n - 1))
    }

    /// Obstacle: the bilinear interpolant at p of the coarse active indicator (1 on active
    /// cells, 0 on free ones and outside the grid, interpolated between the centres of the
    /// four coarse cells nearest to p) is at least [`THRESHOLD`].
    fn predict_cell(&self, p: Point) -> bool {
        let (gx, gy) = self.grid(p);
        let (nx, ny) = (self.nx as isize, self.ny as isize);
        // bilinear interpolation of the 0/1 indicator between the four nearest cell centres
        let (cx, cy) = (gx - 0.5, gy - 0.5);
        let (i0, j0) = (cx.floor() as isize, cy.floor() as isize);
        let (tx, ty) = (cx - i0 as f64, cy - j0 as f64);
        let mut v = 0.0;
        for (dj, wy) in [(0, 1.0 - ty), (1, ty)] {
            for (di, wx) in [(0, 1.0 - tx), (1, tx)] {
                let (a, b) = (i0 + di, j0 + dj);
                let on = a >= 0 && b >= 0 && a < nx && b < ny && self.cells[(b * nx + a) as usize];
                if on {
                    v += wx * wy;
                }
            }
        }
        v >= THRESHOLD - 1e-12
    }

    /// Signorini: the linear interpolant at p of the coarse active indicator along p's side
    /// (between the midpoints of the two coarse faces nearest to p) is at least
    /// [`THRESHOLD`].
    fn predict_face(&self, p: Point) -> bool {
        let (side, g) = self.side_of(p);
        let faces = &self.sides[side];
        let n = faces.len() as isize;
        let c = g - 0.5;
        let i0 = c.floor() as isize;
        let t = c - i0 as f64;
        let on = |i: isize| i >= 0 && i < n && faces[i as usize];
        let v = if on(i0) { 1.0 - t } else { 0.0 } + if on(i0 + 1) { t } else { 0.0 };
        v >= THRESHOLD - 1e-12
    }
}
