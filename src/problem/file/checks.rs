//! The checks of a problem file against a mesh (see [`ProblemFile::check_against_mesh`]), the
//! same in 2D and 3D: a 2D mesh's boundary faces are its edges (centre: the midpoint), a 3D
//! mesh's are polygons (centre: the centroid x_σ).

use super::ProblemFile;
use super::data::{Data, Field, Loc, Part, Piece, select};
use crate::error::{Error, ProblemFileErrorKind as K, Result};
use crate::mesh::PolyMesh;
use crate::mesh3d::PolyMesh3;
use crate::problem::{BoundaryKind, ConstraintKind, check_tensor};
use rayon::prelude::*;

/// What the checks read from a mesh of dimension D.
trait CheckMesh<const D: usize>: Sync {
    /// What a face is called in messages ("edge", "face").
    const FACE: &'static str;
    /// What its centre is called ("midpoint", "centroid").
    const CENTRE: &'static str;
    fn n_cells(&self) -> usize;
    fn centroid(&self, k: usize) -> [f64; D];
    fn cell_tag(&self, k: usize) -> i32;
    /// The vertices of cell `k`.
    fn cell_points(&self, k: usize) -> Vec<[f64; D]>;
    fn n_vertices(&self) -> usize;
    fn vertex(&self, v: usize) -> [f64; D];
    fn n_faces(&self) -> usize;
    /// x_σ.
    fn face_centre(&self, f: usize) -> [f64; D];
    /// The vertices of face `f`.
    fn face_points(&self, f: usize) -> Vec<[f64; D]>;
    fn boundary_faces(&self) -> Vec<usize>;
    fn face_tag(&self, f: usize) -> i32;
}

impl CheckMesh<2> for PolyMesh {
    const FACE: &'static str = "edge";
    const CENTRE: &'static str = "midpoint";
    fn n_cells(&self) -> usize {
        PolyMesh::n_cells(self)
    }
    fn centroid(&self, k: usize) -> [f64; 2] {
        PolyMesh::centroid(self, k)
    }
    fn cell_tag(&self, k: usize) -> i32 {
        PolyMesh::cell_tag(self, k)
    }
    fn cell_points(&self, k: usize) -> Vec<[f64; 2]> {
        let vs = self.cell_vertices(k);
        vs.iter().map(|&v| self.vertex(v as usize)).collect()
    }
    fn n_vertices(&self) -> usize {
        PolyMesh::n_vertices(self)
    }
    fn vertex(&self, v: usize) -> [f64; 2] {
        PolyMesh::vertex(self, v)
    }
    fn n_faces(&self) -> usize {
        self.n_edges()
    }
    fn face_centre(&self, f: usize) -> [f64; 2] {
        self.edge_midpoint(f)
    }
    fn face_points(&self, f: usize) -> Vec<[f64; 2]> {
        self.edge_vertices(f).map(|v| self.vertex(v)).to_vec()
    }
    fn boundary_faces(&self) -> Vec<usize> {
        self.boundary_edges().to_vec()
    }
    fn face_tag(&self, f: usize) -> i32 {
        self.edge_tag(f)
    }
}

impl CheckMesh<3> for PolyMesh3 {
    const FACE: &'static str = "face";
    const CENTRE: &'static str = "centroid";
    fn n_cells(&self) -> usize {
        PolyMesh3::n_cells(self)
    }
    fn centroid(&self, k: usize) -> [f64; 3] {
        PolyMesh3::centroid(self, k)
    }
    fn cell_tag(&self, k: usize) -> i32 {
        PolyMesh3::cell_tag(self, k)
    }
    fn cell_points(&self, k: usize) -> Vec<[f64; 3]> {
        let mut vs: Vec<u32> = self
            .cell_faces(k)
            .iter()
            .flat_map(|&f| self.face_vertices(f as usize).iter().copied())
            .collect();
        vs.sort_unstable();
        vs.dedup();
        vs.iter().map(|&v| self.vertices()[v as usize]).collect()
    }
    fn n_vertices(&self) -> usize {
        PolyMesh3::n_vertices(self)
    }
    fn vertex(&self, v: usize) -> [f64; 3] {
        self.vertices()[v]
    }
    fn n_faces(&self) -> usize {
        PolyMesh3::n_faces(self)
    }
    fn face_centre(&self, f: usize) -> [f64; 3] {
        self.face_centroid(f)
    }
    fn face_points(&self, f: usize) -> Vec<[f64; 3]> {
        let vs = self.face_vertices(f);
        vs.iter().map(|&v| self.vertices()[v as usize]).collect()
    }
    fn boundary_faces(&self) -> Vec<usize> {
        PolyMesh3::boundary_faces(self)
            .iter()
            .map(|&f| f as usize)
            .collect()
    }
    fn face_tag(&self, f: usize) -> i32 {
        PolyMesh3::face_tag(self, f)
    }
}

/// `(a, b)` or `(a, b, c)`.
fn point(p: &[f64]) -> String {
    let parts: Vec<String> = p.iter().map(|v| v.to_string()).collect();
    format!("({})", parts.join(", "))
}

impl ProblemFile {
    /// Checks the problem against the 2D `mesh`: the file is a 2D problem (no `z`, 2×2
    /// tensors, 2 gradient components; else the error of compiling it for 2D, with its place);
    /// every tag of the file is on some boundary edge; every boundary edge is selected by
    /// exactly one boundary section (or taken by the rest); a piece of A and of f applies at
    /// every cell; A is symmetric positive definite at every centroid; and every datum is
    /// finite at every point where a scheme evaluates it:
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
        self.check_against::<2, _>(mesh)
    }

    /// [`ProblemFile::check_against_mesh`] on a 3D mesh: the file is a 3D problem, tags are
    /// boundary-face tags (gmsh physical surfaces) and cell tags (physical volumes), boundary
    /// data is checked at the face centroids x_σ and the face vertices, the obstacle barrier
    /// at x_K, the vertices and every face centroid.
    pub fn check_against_mesh3(&self, mesh: &PolyMesh3) -> Result<()> {
        self.check_against::<3, _>(mesh)
    }

    fn check_against<const D: usize, M: CheckMesh<D>>(&self, mesh: &M) -> Result<()> {
        let d = self.data::<D>()?;
        let c = Checker {
            pf: self,
            d: &d,
            mesh,
        };
        c.check_tags()?;
        let kinds = c.check_boundary()?;
        c.check_cells()?;
        c.check_vertices_and_faces()?;
        c.check_boundary_values(&kinds)
    }
}

/// A file's data for dimension D and a mesh being checked.
struct Checker<'a, const D: usize, M> {
    pf: &'a ProblemFile,
    d: &'a Data<D>,
    mesh: &'a M,
}

impl<const D: usize, M: CheckMesh<D>> Checker<'_, D, M> {
    fn fail(&self, kind: K, loc: &Loc, msg: String) -> Error {
        Error::ProblemFile {
            path: self.pf.path.clone(),
            line: loc.line,
            column: loc.column,
            kind,
            msg: format!("{}: {msg}", loc.key),
        }
    }

    fn check_tags(&self) -> Result<()> {
        let mesh = self.mesh;
        let mut present: Vec<i32> = mesh
            .boundary_faces()
            .iter()
            .map(|&e| mesh.face_tag(e))
            .collect();
        present.sort_unstable();
        present.dedup();
        for part in &self.d.parts {
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
                            "tag {t} is on no boundary {} of the mesh (its boundary tags: {})",
                            M::FACE,
                            list.join(", ")
                        ),
                    ));
                }
            }
        }
        self.check_cell_tags()
    }

    /// Every cell tag named by a piece of A or f is the tag of some cell of the mesh.
    fn check_cell_tags(&self) -> Result<()> {
        let mesh = self.mesh;
        let mut present: Vec<i32> = (0..mesh.n_cells()).map(|k| mesh.cell_tag(k)).collect();
        present.sort_unstable();
        present.dedup();
        let d = self.d;
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

    /// The kind of every boundary face (in the order of `mesh.boundary_faces()`).
    fn check_boundary(&self) -> Result<Vec<BoundaryKind>> {
        let d = self.d;
        let faces = self.mesh.boundary_faces();
        if !d.has_boundary_sections() {
            return Ok(vec![BoundaryKind::Dirichlet; faces.len()]);
        }
        let kinds: Vec<std::result::Result<BoundaryKind, Error>> =
            faces.par_iter().map(|&e| self.face_kind(e)).collect();
        kinds.into_iter().collect()
    }

    fn face_kind(&self, e: usize) -> Result<BoundaryKind> {
        let d = self.d;
        let (x, tag) = (self.mesh.face_centre(e), self.mesh.face_tag(e));
        let place = format!(
            "boundary {} {e} ({} {}, tag {tag})",
            M::FACE,
            M::CENTRE,
            point(&x)
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
    fn check_cells(&self) -> Result<()> {
        let bad = (0..self.mesh.n_cells())
            .into_par_iter()
            .find_map_first(|k| self.cell_error(k).err());
        bad.map_or(Ok(()), Err)
    }

    fn cell_error(&self, k: usize) -> Result<()> {
        let (d, mesh) = (self.d, self.mesh);
        let xk = mesh.centroid(k);
        // formatted only on failure
        let place = || format!("cell {k} (x_K = {})", point(&xk));
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
            let verts = if piecewise {
                mesh.cell_points(k)
            } else {
                Vec::new()
            };
            for p in std::iter::once(xk).chain(verts) {
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
    /// barrier at every face centre (Crouzeix–Raviart).
    fn check_vertices_and_faces(&self) -> Result<()> {
        let (d, mesh) = (self.d, self.mesh);
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
            let bad = (0..mesh.n_faces()).into_par_iter().find_map_first(|e| {
                self.finite(b, mesh.face_centre(e), &|| format!("{} {e}", M::FACE))
                    .err()
            });
            bad.map_or(Ok(()), Err)?;
        }
        Ok(())
    }

    /// `Err` naming the datum, the point and the place if `f` is not finite at `p`.
    fn finite(&self, f: &Field, p: [f64; D], place: &dyn Fn() -> String) -> Result<()> {
        let v = f.at(p);
        if v.is_finite() {
            return Ok(());
        }
        let msg = format!(
            "\"{}\" is {v} at {}, {}",
            f.expr.source(),
            point(&p),
            place()
        );
        Err(self.fail(K::NonFinite, &f.loc, msg))
    }

    /// Dirichlet values, Neumann fluxes and the Signorini barrier on the faces of their kind
    /// (the Dirichlet value and the barrier also at the vertices of the face, for P1).
    fn check_boundary_values(&self, kinds: &[BoundaryKind]) -> Result<()> {
        let (d, mesh) = (self.d, self.mesh);
        let sig = match &d.constraint {
            Some((ConstraintKind::Signorini, _, b)) => Some(b),
            _ => None,
        };
        let bad = mesh
            .boundary_faces()
            .par_iter()
            .zip(kinds)
            .find_map_first(|(&e, kind)| {
                let (field, ends) = match kind {
                    BoundaryKind::Dirichlet => (d.dirichlet.as_ref(), true),
                    BoundaryKind::Neumann => (d.neumann.as_ref(), false),
                    BoundaryKind::Signorini => (sig, true),
                };
                let f = field?;
                let place = || format!("boundary {} {e}", M::FACE);
                let ends = if ends {
                    mesh.face_points(e)
                } else {
                    Vec::new()
                };
                std::iter::once(mesh.face_centre(e))
                    .chain(ends)
                    .find_map(|p| self.finite(f, p, &place).err())
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
