//! The numeric part of assembly for one problem: the data evaluated on the scheme (A_K at x_K,
//! f through the scheme's quadrature, the boundary partition, Dirichlet and Neumann data) and
//! the local matrices and loads the scheme emits for them. Refilled per problem; the symbolic
//! part ([`super::symbolic`]) is shared.

use super::gather::{cell_chunks, chunks, split_by_ranges};
use super::symbolic::DofMap;
use crate::budget::{try_filled, try_resize, try_vec};
use crate::linalg::CsrMatrix;
use crate::mesh::SolveMesh;
use crate::offsets::Offsets;
use crate::problem::{BoundaryKind, Problem, check_finite_at, check_tensor};
use crate::scheme::{GradientDiscretisation, PointDof};
use crate::vi::FixedValues;
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
    /// The Neumann part of the load on the skeleton unknowns; empty (zero) when no boundary
    /// face is of Neumann type.
    pub neumann_load: Vec<f64>,
    /// Dirichlet unknowns and their values.
    pub dirichlet: FixedValues,
    /// Unknowns carrying the trace on Γ3, with their points and measures (Dirichlet ones too).
    pub signorini: Vec<PointDof<D>>,
    /// Schemes without interior unknowns: the global matrix, assembled once
    /// ([`super::assembled`]); `mats` and `loads` are then empty.
    pub assembled: Option<std::sync::Arc<CsrMatrix>>,
}

/// Cells per batch of [`ProblemValues::evaluate_assembled`] (64k tetrahedra: 5 MiB of local
/// matrices).
const BATCH: usize = 1 << 16;

/// What one parallel task of [`fill_local`] found wrong in its cells (the first of each kind).
#[derive(Default)]
struct ChunkDefects {
    bad_tensor: Option<crate::Error>,
    bad_source: Option<String>,
    /// The scheme emitted a local system of another size than the cell's unknowns.
    bad_size: Option<String>,
}

impl<const D: usize> ProblemValues<D> {
    /// Evaluates the data of `problem` on `scheme` (whose dof map is `dm`).
    pub fn evaluate<M: SolveMesh<D> + ?Sized>(
        scheme: &dyn GradientDiscretisation<M, D>,
        dm: &DofMap,
        problem: &Problem<D>,
    ) -> crate::Result<Self> {
        let (mat_ptr, mats, loads) = local_data(scheme, dm, problem)?;
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
            neumann_load: Vec::new(),
            dirichlet: FixedValues::free(n)?,
            signorini: Vec::new(),
            assembled: None,
        };
        values.boundary_conditions(scheme, problem)?;
        Ok(values)
    }

    /// For a scheme without interior unknowns (P1, CR): the data, with the global matrix
    /// assembled on the lower pattern `pattern` of the condensed matrix instead of the local
    /// matrices ([`super::assembled`]). The cells go by batches of `BATCH` (65 536): their local
    /// matrices and loads are computed in parallel, then added into M and b in cell order
    /// (so M and b have the bits of the gathered ones), and the batch's buffers reused.
    pub fn evaluate_assembled<M: SolveMesh<D> + ?Sized>(
        scheme: &dyn GradientDiscretisation<M, D>,
        dm: &DofMap,
        pattern: (&[usize], &[usize]),
        problem: &Problem<D>,
    ) -> crate::Result<Self> {
        let nc = scheme.mesh().n_cells();
        let mat_ptr = local_offsets(dm)?;
        let mut lower = try_filled(pattern.1.len(), 0.0, "the assembled matrix")?;
        let mut load = try_filled(scheme.n_unknowns(), 0.0, "the load vector")?;
        let (mut mats, mut loads) = (Vec::new(), Vec::new());
        for (b0, b1) in chunks(nc, BATCH) {
            let (l0, l1) = (dm.dof_ptr.at(b0), dm.dof_ptr.at(b1));
            try_resize(
                &mut mats,
                mat_ptr.at(b1) - mat_ptr.at(b0),
                0.0,
                "the local matrices",
            )?;
            try_resize(&mut loads, l1 - l0, 0.0, "the local loads")?;
            fill_local(
                scheme,
                dm,
                problem,
                (b0, b1),
                &mat_ptr,
                &mut mats,
                &mut loads,
            )?;
            super::assembled::scatter(dm, (b0, b1), pattern, &mats, &mat_ptr, &mut lower)?;
            for (&d, &l) in dm.dofs[l0..l1].iter().zip(&loads) {
                load[d as usize] += l;
            }
        }
        drop((mats, loads));
        let (col_ptr, row_idx) = pattern;
        let mut a = CsrMatrix::from_lower_csc(col_ptr.len() - 1, col_ptr, row_idx, &lower)?;
        drop(lower);
        a.drop_zeros();
        let mut values = ProblemValues {
            mat_ptr: Offsets::from_lengths(std::iter::empty())?,
            mats: Vec::new(),
            loads: Vec::new(),
            load,
            neumann_load: Vec::new(),
            dirichlet: FixedValues::free(scheme.n_unknowns())?,
            signorini: Vec::new(),
            assembled: Some(std::sync::Arc::new(a)),
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
                        let v = check_finite_at((problem.dirichlet)(t.point), || {
                            format!("the Dirichlet value at {:?}", t.point)
                        })?;
                        self.dirichlet.set(t.dof, v);
                    }
                }
                BoundaryKind::Neumann => {
                    let g = check_finite_at((problem.neumann)(xs), || {
                        format!("the Neumann flux at {xs:?}")
                    })?;
                    if self.neumann_load.is_empty() {
                        self.neumann_load =
                            try_filled(scheme.n_skeleton(), 0.0, "the Neumann load")?;
                    }
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

/// The offsets of the packed local matrices on the dof map `dm`: cell k's has
/// packed_len(p_k) entries, p_k its number of unknowns.
fn local_offsets(dm: &DofMap) -> crate::Result<Offsets> {
    Offsets::from_lengths(
        (0..dm.n_cells()).map(|k| super::condense::packed_len(dm.dof_ptr.range(k).len())),
    )
}

/// The local matrices (for A_K = A(x_K)) and loads of every cell, written in place into arrays
/// laid out by the dof map `dm` ([`local_offsets`] for the matrices; the loads like the
/// unknowns) and allocated once, before the cells are visited, so that no per-chunk copy is
/// ever held beside them.
fn local_data<M: SolveMesh<D> + ?Sized, const D: usize>(
    scheme: &dyn GradientDiscretisation<M, D>,
    dm: &DofMap,
    problem: &Problem<D>,
) -> crate::Result<(Offsets, Vec<f64>, Vec<f64>)> {
    let nc = scheme.mesh().n_cells();
    let mat_ptr = local_offsets(dm)?;
    let mut mats = try_filled(mat_ptr.total(), 0.0, "the local matrices")?;
    let mut loads = try_filled(dm.dofs.len(), 0.0, "the local loads")?;
    fill_local(
        scheme,
        dm,
        problem,
        (0, nc),
        &mat_ptr,
        &mut mats,
        &mut loads,
    )?;
    Ok((mat_ptr, mats, loads))
}

/// The local matrices and loads of the cells `b0..b1` into `mats` and `loads` (laid out by
/// `mat_ptr` and the dof map `dm`, from the batch's first cell), in parallel over chunks of
/// cells. The first bad tensor in cell order is the error, then the first non-finite load, as
/// in a sequential loop.
fn fill_local<M: SolveMesh<D> + ?Sized, const D: usize>(
    scheme: &dyn GradientDiscretisation<M, D>,
    dm: &DofMap,
    problem: &Problem<D>,
    (b0, b1): (usize, usize),
    mat_ptr: &Offsets,
    mats: &mut [f64],
    loads: &mut [f64],
) -> crate::Result<()> {
    let mesh = scheme.mesh();
    let ranges: Vec<_> = cell_chunks(b1 - b0)
        .into_iter()
        .map(|(c0, c1)| (b0 + c0, b0 + c1))
        .collect();
    let m_slices = split_by_ranges(mats, &ranges, |k| mat_ptr.at(k));
    let l_slices = split_by_ranges(loads, &ranges, |k| dm.dof_ptr.at(k));
    let tasks: Vec<_> = ranges.into_iter().zip(m_slices).zip(l_slices).collect();
    let defects: Vec<ChunkDefects> = tasks
        .into_par_iter()
        .map(|(((c0, c1), ms), ls)| {
            let mut out = ChunkDefects::default();
            let mut m = DMatrix::zeros(0, 0);
            let mut b = DVector::zeros(0);
            let (m0, l0) = (mat_ptr.at(c0), dm.dof_ptr.at(c0));
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
                let p = dm.dof_ptr.range(k).len();
                if m.nrows() != p || m.ncols() != p || b.len() != p {
                    out.bad_size = Some(format!(
                        "cell {k}: a local matrix of {}×{} and a load of {} for {p} unknowns",
                        m.nrows(),
                        m.ncols(),
                        b.len()
                    ));
                    break;
                }
                if out.bad_source.is_none() && b.iter().any(|x| !x.is_finite()) {
                    out.bad_source = Some(format!(
                        "the source term f is not finite in cell {k} (x_K = {xk:?})"
                    ));
                }
                // symmetric: the lower triangle only
                let mr = mat_ptr.range(k);
                super::condense::pack_lower(p, m.as_slice(), &mut ms[mr.start - m0..mr.end - m0]);
                let lr = dm.dof_ptr.range(k);
                ls[lr.start - l0..lr.end - l0].copy_from_slice(b.as_slice());
            }
            out
        })
        .collect();
    let mut defects = defects;
    if let Some(msg) = defects.iter_mut().find_map(|c| c.bad_size.take()) {
        return Err(crate::Error::Internal(msg));
    }
    if let Some(e) = defects.iter_mut().find_map(|c| c.bad_tensor.take()) {
        return Err(e);
    }
    if let Some(msg) = defects.iter().find_map(|c| c.bad_source.clone()) {
        return Err(crate::Error::InvalidData(msg));
    }
    Ok(())
}
