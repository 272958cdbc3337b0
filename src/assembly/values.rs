//! The numeric part of assembly for one problem: the data evaluated on the scheme (A_K at x_K,
//! f through the scheme's quadrature, the boundary partition, Dirichlet and Neumann data) and
//! the local matrices and loads the scheme emits for them. Refilled per problem; the symbolic
//! part ([`super::symbolic`]) is shared.

use super::gather::cell_chunks;
use super::offsets::Offsets;
use super::symbolic::DofMap;
use crate::mesh::SolveMesh;
use crate::mesh::budget::{AllocFailure, try_filled, try_grow, try_vec};
use crate::problem::{BoundaryKind, Problem, check_finite, check_tensor};
use crate::scheme::{GradientDiscretisation, PointDof};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// The local matrices and loads of every cell, and the boundary data, for one problem.
#[derive(Debug, Clone)]
pub struct ProblemValues<const D: usize = 2> {
    /// Offsets into `mats`, one per cell plus one.
    pub mat_ptr: Offsets,
    /// The local matrices (symmetric), their lower triangles column by column
    /// ([`super::condense::packed_index`]), in the order of the cell's unknowns.
    pub mats: Vec<f64>,
    /// The local loads, laid out like [`DofMap::dofs`].
    pub loads: Vec<f64>,
    /// Full load vector b (local loads and Neumann data), indexed by unknown.
    pub load: Vec<f64>,
    /// The Neumann part of the load on the skeleton unknowns.
    pub neumann_load: Vec<f64>,
    /// Dirichlet unknowns and their values.
    pub dirichlet: Vec<Option<f64>>,
    /// Unknowns carrying the trace on Γ3, with their points and measures (Dirichlet ones too).
    pub signorini: Vec<PointDof<D>>,
}

/// What one parallel task of [`local_data`] computes for its cells.
#[derive(Default)]
struct LocalChunk {
    mat_len: Vec<usize>,
    mats: Vec<f64>,
    loads: Vec<f64>,
    bad_tensor: Option<crate::Error>,
    bad_source: Option<String>,
    /// The chunk's buffers could not grow: it stopped at that cell.
    no_memory: Option<AllocFailure>,
}

impl<const D: usize> ProblemValues<D> {
    /// Evaluates the data of `problem` on `scheme` (whose dof map is `dm`).
    pub fn evaluate<M: SolveMesh<D> + ?Sized>(
        scheme: &dyn GradientDiscretisation<M, D>,
        dm: &DofMap,
        problem: &Problem<D>,
    ) -> crate::Result<Self> {
        let (mat_ptr, mats, loads) = local_data(scheme, problem)?;
        let n = scheme.n_unknowns();
        let mut load = try_filled(n, 0.0, "the load vector")?;
        for (i, &d) in dm.dofs.iter().enumerate() {
            load[d as usize] += loads[i];
        }
        let mut values = ProblemValues {
            mat_ptr,
            mats,
            loads,
            load,
            neumann_load: try_filled(scheme.n_skeleton(), 0.0, "the Neumann load")?,
            dirichlet: try_filled(n, None, "the Dirichlet values")?,
            signorini: Vec::new(),
        };
        values.boundary_conditions(scheme, problem)?;
        Ok(values)
    }

    /// Dirichlet values, Neumann loads and the Signorini unknowns, face by face of ∂Ω (edges
    /// in 2D), the boundary kind and the Neumann flux taken at the face centre x_σ.
    fn boundary_conditions<M: SolveMesh<D> + ?Sized>(
        &mut self,
        scheme: &dyn GradientDiscretisation<M, D>,
        problem: &Problem<D>,
    ) -> crate::Result<()> {
        let mesh = scheme.mesh();
        let n = scheme.n_unknowns();
        let mut sig_meas: Vec<f64> = try_filled(n, 0.0, "the Signorini measures")?;
        let mut sig_point: Vec<Option<[f64; D]>> = try_filled(n, None, "the Signorini points")?;
        let mut tr = Vec::new();
        for i in 0..mesh.n_boundary_faces() {
            let e = mesh.boundary_face(i);
            let xs = mesh.face_centre(e);
            let kind = (problem.boundary)(xs, mesh.face_tag(e));
            scheme.face_trace_dofs(e, &mut tr);
            match kind {
                BoundaryKind::Dirichlet => {
                    for t in &tr {
                        let v = check_finite(
                            (problem.dirichlet)(t.point),
                            &format!("the Dirichlet value at {:?}", t.point),
                        )?;
                        self.dirichlet[t.dof] = Some(v);
                    }
                }
                BoundaryKind::Neumann => {
                    let g = check_finite(
                        (problem.neumann)(xs),
                        &format!("the Neumann flux at {xs:?}"),
                    )?;
                    for t in &tr {
                        self.load[t.dof] += t.measure * g;
                        self.neumann_load[t.dof] += t.measure * g;
                    }
                }
                BoundaryKind::Signorini => {
                    for t in &tr {
                        sig_meas[t.dof] += t.measure;
                        sig_point[t.dof] = Some(t.point);
                    }
                }
            }
        }
        // Γ3 carries natural (zero-flux) data where inactive: nothing to add to the load.
        let n_sig = sig_point.iter().filter(|p| p.is_some()).count();
        self.signorini = try_vec(n_sig, "the Signorini unknowns")?;
        self.signorini.extend((0..n).filter_map(|d| {
            sig_point[d].map(|point| PointDof {
                dof: d,
                point,
                measure: sig_meas[d],
            })
        }));
        Ok(())
    }
}

/// The local matrices (for A_K = A(x_K)) and loads of every cell, in parallel over chunks of
/// cells, concatenated in cell order; the first bad tensor or non-finite load in cell order is
/// the error, as in a sequential loop.
fn local_data<M: SolveMesh<D> + ?Sized, const D: usize>(
    scheme: &dyn GradientDiscretisation<M, D>,
    problem: &Problem<D>,
) -> crate::Result<(Offsets, Vec<f64>, Vec<f64>)> {
    let mesh = scheme.mesh();
    let nc = mesh.n_cells();
    let chunks: Vec<LocalChunk> = cell_chunks(nc)
        .into_par_iter()
        .map(|(c0, c1)| {
            let mut out = LocalChunk::default();
            let mut m = DMatrix::zeros(0, 0);
            let mut b = DVector::zeros(0);
            for k in c0..c1 {
                let xk = mesh.cell_centre(k);
                let tag = mesh.cell_tag(k);
                let a = problem.diffusion_in(xk, tag);
                // the message is formatted only for a bad tensor
                if check_tensor(&a, "").is_err() {
                    out.bad_tensor = check_tensor(&a, &format!("x_K = {xk:?} (cell {k})")).err();
                    break;
                }
                scheme.local_matrix(k, &a, &mut m);
                let f = |p: [f64; D]| -> f64 { problem.source_in(p, xk, tag) };
                scheme.local_load(k, &f, &mut b);
                if out.bad_source.is_none() && b.iter().any(|x| !x.is_finite()) {
                    out.bad_source = Some(format!(
                        "the source term f is not finite in cell {k} (x_K = {xk:?})"
                    ));
                }
                // symmetric: the lower triangle only
                let (n, start) = (m.nrows(), out.mats.len());
                let len = super::condense::packed_len(n);
                let room = try_grow(&mut out.mats, len, "the local matrices")
                    .and_then(|()| try_grow(&mut out.loads, b.len(), "the local loads"))
                    .and_then(|()| try_grow(&mut out.mat_len, 1, "the local matrices"));
                if let Err(f) = room {
                    out.no_memory = Some(f);
                    break;
                }
                out.mats.resize(start + len, 0.0);
                super::condense::pack_lower(n, m.as_slice(), &mut out.mats[start..]);
                out.mat_len.push(len);
                out.loads.extend(b.iter());
            }
            out
        })
        .collect();
    let mut chunks = chunks;
    if let Some(f) = chunks.iter_mut().find_map(|c| c.no_memory.take()) {
        return Err(f.into());
    }
    if let Some(e) = chunks.iter_mut().find_map(|c| c.bad_tensor.take()) {
        return Err(e);
    }
    if let Some(msg) = chunks.iter().find_map(|c| c.bad_source.clone()) {
        return Err(crate::Error::InvalidData(msg));
    }
    let mat_ptr = Offsets::from_lengths(chunks.iter().flat_map(|c| c.mat_len.iter().copied()))?;
    let mut mats = try_vec(mat_ptr.total(), "the local matrices")?;
    let loads_len = chunks.iter().map(|c| c.loads.len()).sum();
    let mut loads = try_vec(loads_len, "the local loads")?;
    for c in chunks {
        mats.extend_from_slice(&c.mats);
        loads.extend_from_slice(&c.loads);
    }
    Ok((mat_ptr, mats, loads))
}
