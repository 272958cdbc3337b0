//! The checks of a problem file against a mesh (see [`ProblemFile::check_against_mesh`]).

use super::ProblemFile;
use super::data::{Field, Loc, Part, Piece, select};
use crate::error::{Error, ProblemFileErrorKind as K, Result};
use crate::mesh::{Point, PolyMesh};
use crate::problem::{BoundaryKind, ConstraintKind, check_tensor};
use rayon::prelude::*;

impl ProblemFile {
    /// Checks the problem against `mesh`: every tag of the file is on some boundary edge; every
    /// boundary edge is selected by exactly one boundary section (or taken by the rest); a piece
    /// of A and of f applies at every cell; A is symmetric positive definite at every centroid;
    /// and every datum is finite at every point where a scheme evaluates it:
    ///
    /// | datum | points | used there by |
    /// |---|---|---|
    /// | A, exact u and ∇u | cell centroids x_K | every scheme; errors |
    /// | f | x_K and the vertices (piecewise f: the vertices of each cell, with its piece) | HMM; P1 |
    /// | obstacle barrier | x_K, vertices, edge midpoints | HMM; P1; CR |
    /// | Dirichlet value, Signorini barrier | midpoints and end points of the edges of that kind | HMM, CR; P1 |
    /// | Neumann flux | midpoints of the Neumann edges | every scheme |
    ///
    /// (Other quadrature points, such as CR's sub-triangle centroids for f, are checked by the
    /// assembler.) The first failure, in cell, vertex, then edge order, is reported, naming the
    /// key, the cell, vertex or edge, and the point. Cost: a few evaluations per cell, in
    /// parallel.
    pub fn check_against_mesh(&self, mesh: &PolyMesh) -> Result<()> {
        self.check_tags(mesh)?;
        let kinds = self.check_boundary(mesh)?;
        self.check_cells(mesh)?;
        self.check_vertices_and_edges(mesh)?;
        self.check_boundary_values(mesh, &kinds)
    }

    fn fail(&self, kind: K, loc: &Loc, msg: String) -> Error {
        Error::ProblemFile {
            path: self.path.clone(),
            line: loc.line,
            column: loc.column,
            kind,
            msg: format!("{}: {msg}", loc.key),
        }
    }

    fn check_tags(&self, mesh: &PolyMesh) -> Result<()> {
        let mut present: Vec<i32> = mesh
            .boundary_edges()
            .iter()
            .map(|&e| mesh.edge_tag(e))
            .collect();
        present.sort_unstable();
        present.dedup();
        for part in &self.data.parts {
            for t in &part.tags {
                if present.binary_search(t).is_err() {
                    let loc = part.tags_loc.clone().unwrap_or_else(|| Loc {
                        key: format!("{}.tags", part.section),
                        line: 0,
                        column: 0,
                    });
                    let list: Vec<String> = present.iter().map(i32::to_string).collect();
                    return Err(self.fail(
                        K::Tag,
                        &loc,
                        format!(
                            "tag {t} is on no boundary edge of the mesh (its boundary tags: {})",
                            list.join(", ")
                        ),
                    ));
                }
            }
        }
        self.check_cell_tags(mesh)
    }

    /// Every cell tag named by a piece of A or f is the tag of some cell of the mesh.
    fn check_cell_tags(&self, mesh: &PolyMesh) -> Result<()> {
        let mut present: Vec<i32> = (0..mesh.n_cells()).map(|k| mesh.cell_tag(k)).collect();
        present.sort_unstable();
        present.dedup();
        let d = &self.data;
        let named = d
            .diffusion
            .iter()
            .map(|p| ("diffusion.piece", &p.tags, &p.tags_loc))
            .chain(
                d.source
                    .iter()
                    .map(|p| ("source.piece", &p.tags, &p.tags_loc)),
            );
        for (key, tags, tags_loc) in named {
            if let Some(t) = tags.iter().find(|t| present.binary_search(t).is_err()) {
                let list: Vec<String> = present.iter().map(i32::to_string).collect();
                let loc = tags_loc.clone().unwrap_or_else(|| Loc {
                    key: format!("{key}.tags"),
                    line: 0,
                    column: 0,
                });
                return Err(self.fail(
                    K::Tag,
                    &loc,
                    format!(
                        "cell tag {t} is on no cell of the mesh (its cell tags: {})",
                        list.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The kind of every boundary edge (in the order of `mesh.boundary_edges()`).
    fn check_boundary(&self, mesh: &PolyMesh) -> Result<Vec<BoundaryKind>> {
        let d = &self.data;
        let edges = mesh.boundary_edges();
        if !d.has_boundary_sections() {
            return Ok(vec![BoundaryKind::Dirichlet; edges.len()]);
        }
        let kinds: Vec<std::result::Result<BoundaryKind, Error>> =
            edges.par_iter().map(|&e| self.edge_kind(mesh, e)).collect();
        kinds.into_iter().collect()
    }

    fn edge_kind(&self, mesh: &PolyMesh, e: usize) -> Result<BoundaryKind> {
        let d = &self.data;
        let (x, tag) = (mesh.edge_midpoint(e), mesh.edge_tag(e));
        let place = format!(
            "boundary edge {e} (midpoint ({}, {}), tag {tag})",
            x[0], x[1]
        );
        let mut chosen: Option<&Part> = None;
        for p in &d.parts {
            match p.selects(x, tag) {
                None => {
                    let loc = p.cond.as_ref().map_or_else(
                        || {
                            p.tags_loc.clone().unwrap_or(Loc {
                                key: p.section.into(),
                                line: 0,
                                column: 0,
                            })
                        },
                        |c| c.loc.clone(),
                    );
                    return Err(self.fail(
                        K::NonFinite,
                        &loc,
                        format!("the condition is NaN at {place}"),
                    ));
                }
                Some(true) => {
                    if let Some(q) = chosen {
                        let loc = Loc {
                            key: format!("[{}] and [{}]", q.section, p.section),
                            line: 0,
                            column: 0,
                        };
                        return Err(self.fail(
                            K::OverlappingRules,
                            &loc,
                            format!("both select {place}"),
                        ));
                    }
                    chosen = Some(p);
                }
                Some(false) => {}
            }
        }
        match (chosen, d.rest) {
            (Some(p), _) => Ok(p.kind),
            (None, Some((k, _))) => Ok(k),
            (None, None) => {
                let names: Vec<String> =
                    d.parts.iter().map(|p| format!("[{}]", p.section)).collect();
                let loc = Loc {
                    key: "boundary".into(),
                    line: 0,
                    column: 0,
                };
                Err(self.fail(
                    K::UncoveredEdge,
                    &loc,
                    format!("{place} is selected by none of {}; add its tag or widen a 'where', or leave one section without 'tags' and 'where' to take the rest", names.join(", ")),
                ))
            }
        }
    }

    /// Per cell: the pieces of A and f apply, A is SPD; f (piecewise: also at the vertices of
    /// the cell, with its piece), the obstacle barrier and the exact solution are finite at x_K.
    fn check_cells(&self, mesh: &PolyMesh) -> Result<()> {
        let bad = (0..mesh.n_cells())
            .into_par_iter()
            .find_map_first(|k| self.cell_error(mesh, k).err());
        bad.map_or(Ok(()), Err)
    }

    fn cell_error(&self, mesh: &PolyMesh, k: usize) -> Result<()> {
        let d = &self.data;
        let xk = mesh.centroid(k);
        // formatted only on failure
        let place = || format!("cell {k} (x_K = ({}, {}))", xk[0], xk[1]);
        let uncovered = |key: &str| {
            let loc = Loc {
                key: key.into(),
                line: 0,
                column: 0,
            };
            let msg = format!("no piece applies at {}", place());
            self.fail(K::UncoveredPoint, &loc, msg)
        };
        if !d.diffusion.is_empty() {
            let a =
                select(&d.diffusion, xk, mesh.cell_tag(k)).ok_or_else(|| uncovered("diffusion"))?;
            let t = a.at(xk);
            if !t.iter().flatten().all(|v| v.is_finite()) {
                let msg = format!("A = {t:?} at {}", place());
                return Err(self.fail(K::NonFinite, a.loc(), msg));
            }
            if check_tensor(&t, "").is_err() {
                let msg = match check_tensor(&t, &place()) {
                    Err(Error::InvalidData(m)) => m,
                    other => format!("{other:?}"),
                };
                return Err(self.fail(K::NotSpd, a.loc(), msg));
            }
        }
        if !d.source.is_empty() {
            let f = select(&d.source, xk, mesh.cell_tag(k)).ok_or_else(|| uncovered("source"))?;
            let piecewise = d.source.iter().any(|p| p.cond.is_some());
            let verts = mesh
                .cell_vertices(k)
                .iter()
                .map(|&v| mesh.vertex(v as usize));
            let n = if piecewise { usize::MAX } else { 0 };
            for p in std::iter::once(xk).chain(verts.take(n)) {
                self.finite(f, p, &place)?;
            }
        }
        if let Some((ConstraintKind::Obstacle, _, b)) = &d.constraint {
            self.finite(b, xk, &place)?;
        }
        if let Some((u, g)) = &d.exact {
            for f in std::iter::once(u).chain(g) {
                self.finite(f, xk, &place)?;
            }
        }
        Ok(())
    }

    /// An unpiecewise source and the obstacle barrier at every vertex (P1), and the obstacle
    /// barrier at every edge midpoint (Crouzeix–Raviart).
    fn check_vertices_and_edges(&self, mesh: &PolyMesh) -> Result<()> {
        let d = &self.data;
        let source = match d.source.as_slice() {
            [
                Piece {
                    cond: None,
                    value,
                    tags,
                    ..
                },
            ] if tags.is_empty() => Some(value),
            _ => None,
        };
        let obstacle = match &d.constraint {
            Some((ConstraintKind::Obstacle, _, b)) => Some(b),
            _ => None,
        };
        let at_vertices = source.into_iter().chain(obstacle);
        for f in at_vertices {
            let bad = (0..mesh.n_vertices()).into_par_iter().find_map_first(|v| {
                self.finite(f, mesh.vertex(v), &|| format!("vertex {v}"))
                    .err()
            });
            bad.map_or(Ok(()), Err)?;
        }
        if let Some(b) = obstacle {
            let bad = (0..mesh.n_edges()).into_par_iter().find_map_first(|e| {
                self.finite(b, mesh.edge_midpoint(e), &|| format!("edge {e}"))
                    .err()
            });
            bad.map_or(Ok(()), Err)?;
        }
        Ok(())
    }

    /// `Err` naming the datum, the point and the place if `f` is not finite at `p`.
    fn finite(&self, f: &Field, p: Point, place: &dyn Fn() -> String) -> Result<()> {
        let v = f.at(p);
        if v.is_finite() {
            return Ok(());
        }
        let msg = format!(
            "\"{}\" is {v} at ({}, {}), {}",
            f.expr.source(),
            p[0],
            p[1],
            place()
        );
        Err(self.fail(K::NonFinite, &f.loc, msg))
    }

    /// Dirichlet values, Neumann fluxes and the Signorini barrier on the edges of their kind
    /// (the Dirichlet value and the barrier also at the end points, for P1).
    fn check_boundary_values(&self, mesh: &PolyMesh, kinds: &[BoundaryKind]) -> Result<()> {
        let d = &self.data;
        let sig = match &d.constraint {
            Some((ConstraintKind::Signorini, _, b)) => Some(b),
            _ => None,
        };
        let bad = mesh
            .boundary_edges()
            .par_iter()
            .zip(kinds)
            .find_map_first(|(&e, kind)| {
                let (field, ends) = match kind {
                    BoundaryKind::Dirichlet => (d.dirichlet.as_ref(), true),
                    BoundaryKind::Neumann => (d.neumann.as_ref(), false),
                    BoundaryKind::Signorini => (sig, true),
                };
                let f = field?;
                let place = || format!("boundary edge {e}");
                let [a, b] = mesh.edge_vertices(e).map(|v| mesh.vertex(v));
                let pts = [mesh.edge_midpoint(e), a, b];
                let n = if ends { 3 } else { 1 };
                pts[..n]
                    .iter()
                    .find_map(|&p| self.finite(f, p, &place).err())
            });
        bad.map_or(Ok(()), Err)
    }
}

#[cfg(test)]
mod tests {
    use crate::error::{Error, ProblemFileErrorKind as K};
    use crate::mesh::PolyMesh;
    use crate::problem::file::parse;
    use std::path::Path;

    /// The unit square cut into two squares: cells [0, 0.5] × [0, 1] and [0.5, 1] × [0, 1].
    fn two_squares() -> PolyMesh {
        let v = (0..6).map(|i| [0.5 * (i % 3) as f64, (i / 3) as f64]);
        PolyMesh::from_cells(v.collect(), vec![vec![0, 1, 4, 3], vec![1, 2, 5, 4]]).unwrap()
    }

    /// The kind and message of the first failure of the file `text` on [`two_squares`].
    fn failure(text: &str) -> Option<(K, String)> {
        let pf = parse(text, Path::new("t.toml"), &[]).unwrap();
        match pf.check_against_mesh(&two_squares()) {
            Ok(()) => None,
            Err(Error::ProblemFile { kind, msg, .. }) => Some((kind, msg)),
            Err(e) => panic!("{e:?}"),
        }
    }

    #[test]
    fn data_is_checked_where_the_schemes_evaluate_it() {
        assert_eq!(
            failure("[source]\nf = \"1/x\"\n[obstacle]\nside = \"upper\"\nbarrier = 1"),
            {
                let msg = "source.f: \"1/x\" is inf at (0, 0), vertex 0";
                Some((K::NonFinite, msg.to_string()))
            }
        );
        // an obstacle barrier also at the edge midpoints: only (0.75, 1) fails
        let text = "[obstacle]\nside = \"upper\"\nbarrier = \"1/(x + 2*y - 2.75)\"";
        let (kind, msg) = failure(text).unwrap();
        assert_eq!(kind, K::NonFinite);
        let at = "obstacle.barrier: \"1/(x + 2*y - 2.75)\" is inf at (0.75, 1), edge ";
        assert!(msg.starts_with(at), "{msg}");
        assert_eq!(failure("[source]\nf = \"1/(x + 2)\""), None);
    }

    #[test]
    fn boundary_edges_are_selected_once() {
        let (dirichlet, neumann) = (
            "[dirichlet]\nwhere = \"x < ",
            "\"\n[neumann]\nwhere = \"x > ",
        );
        let cases = [
            // the top and bottom edges are selected by neither section
            (
                "0.1",
                "0.9",
                K::UncoveredEdge,
                "is selected by none of [dirichlet], [neumann]",
            ),
            // the two edges with midpoint x = 0.25 by both
            (
                "0.6",
                "0.2",
                K::OverlappingRules,
                "[dirichlet] and [neumann]: both select",
            ),
        ];
        for (d, n, kind, fragment) in cases {
            let (k, msg) = failure(&format!("{dirichlet}{d}{neumann}{n}\"")).unwrap();
            assert_eq!(k, kind, "{msg}");
            assert!(msg.contains(fragment), "{msg}");
        }
        // a section without selection takes the rest
        let rest = "[dirichlet]\nwhere = \"x < 0.6\"\n[neumann]\n";
        assert_eq!(failure(rest), None);
    }
}
