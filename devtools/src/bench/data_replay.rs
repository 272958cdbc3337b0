//! The data evaluations a solve makes, recorded and replayed: the measurement behind the peer
//! benchmark's data-evaluation share (the problem-files issue's "data evaluation under 10% of
//! a 10⁶-cell solve").
//!
//! [`record`] wraps every closure of a [`Problem`] (A, f in its three forms, the boundary
//! partition, the Dirichlet and Neumann data, the barrier, the exact solution and its
//! gradient) in one that appends its arguments to a log before calling the original. A solve
//! of the recording problem, untimed, leaves in the logs every evaluation the solve made, at
//! the points where it made them (the coarse levels of the nested start included), and so do
//! the error computations that follow it. [`Recorded::replay_seconds`] then evaluates the
//! original closures again at every logged argument, on the threads of rayon's pool (those of
//! the solve), and times that alone: the time the solve spent evaluating its data, without the
//! work around each call (finding the point) and without the logging. The bound of
//! `peers::data_seconds` (every datum at every centroid, edge midpoint and vertex) counts
//! evaluations that no scheme makes.

use gradvi::problem::{BoundaryKind, Problem};
use gradvi::scheme::Tensor;
use rayon::prelude::*;
use std::convert::identity;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Instant;

/// A datum as a function of one argument (a point, or a tuple of a point and its cell's data).
type Shared<A, R> = Arc<dyn Fn(A) -> R + Send + Sync>;

/// The log of one datum: its original closure, the arguments it was called with, and how to
/// reduce a value to one number (so that the replay's values are used, not optimised away).
struct Log<A, R> {
    name: &'static str,
    f: Shared<A, R>,
    args: Arc<Mutex<Vec<A>>>,
    reduce: fn(R) -> f64,
}

/// A log of any datum, replayable.
trait Replay: Send + Sync {
    /// The datum's name.
    fn name(&self) -> &'static str;
    /// Evaluates the datum at every logged argument (on rayon's pool); the number of
    /// evaluations and the sum of the reduced values.
    fn replay(&self) -> (usize, f64);
}

impl<A: Copy + Send + Sync, R> Replay for Log<A, R> {
    fn name(&self) -> &'static str {
        self.name
    }

    fn replay(&self) -> (usize, f64) {
        let args = self.args.lock().unwrap_or_else(PoisonError::into_inner);
        let sum = args
            .par_iter()
            .with_min_len(4096)
            .map(|&a| (self.reduce)((self.f)(a)))
            .sum();
        (args.len(), sum)
    }
}

/// The logs of a recording problem (see [`record`]).
pub struct Recorded {
    logs: Vec<Box<dyn Replay>>,
}

/// The result of a replay.
pub struct Replayed {
    /// Seconds to evaluate every logged call again, on rayon's pool.
    pub seconds: f64,
    /// Number of evaluations.
    pub evaluations: usize,
    /// Number of evaluations of each datum, by name, in the order of [`record`].
    pub by_datum: Vec<(&'static str, usize)>,
}

impl Recorded {
    /// Evaluates every datum again at every argument logged so far, timed (see the module
    /// docs).
    pub fn replay_seconds(&self) -> Replayed {
        let t = Instant::now();
        let (mut evaluations, mut sum, mut by_datum) = (0, 0.0, Vec::new());
        for log in &self.logs {
            let (n, s) = log.replay();
            evaluations += n;
            sum += s;
            by_datum.push((log.name(), n));
        }
        let seconds = t.elapsed().as_secs_f64();
        std::hint::black_box(sum);
        Replayed {
            seconds,
            evaluations,
            by_datum,
        }
    }
}

/// `f` wrapped so that every call logs its argument; the log goes to `logs`.
fn logged<A, R>(
    name: &'static str,
    f: Shared<A, R>,
    reduce: fn(R) -> f64,
    logs: &mut Recorded,
) -> Shared<A, R>
where
    A: Copy + Send + Sync + 'static,
    R: 'static,
{
    let args: Arc<Mutex<Vec<A>>> = Arc::new(Mutex::new(Vec::new()));
    logs.logs.push(Box::new(Log {
        name,
        f: f.clone(),
        args: args.clone(),
        reduce,
    }));
    Arc::new(move |a| {
        args.lock().unwrap_or_else(PoisonError::into_inner).push(a);
        f(a)
    })
}

fn tensor_sum(a: Tensor<2>) -> f64 {
    a.iter().flatten().sum()
}

fn vector_sum(v: [f64; 2]) -> f64 {
    v[0] + v[1]
}

fn kind(k: BoundaryKind) -> f64 {
    k as usize as f64
}

/// A closure that does nothing, left for an instant in a field being wrapped.
fn placeholder<R: Default>() -> Box<dyn Fn([f64; 2]) -> R + Send + Sync> {
    Box::new(|_| R::default())
}

/// A scalar field of a problem, recorded.
fn scalar_field(
    name: &'static str,
    f: &mut Box<dyn Fn([f64; 2]) -> f64 + Send + Sync>,
    logs: &mut Recorded,
) {
    let g: Shared<[f64; 2], f64> = Arc::from(std::mem::replace(f, placeholder()));
    let w = logged(name, g, identity, logs);
    *f = Box::new(move |x| w(x));
}

/// `problem` with every closure recorded, and the logs.
pub fn record(mut problem: Problem) -> (Problem, Recorded) {
    let mut logs = Recorded { logs: Vec::new() };
    let p = &mut problem;
    let a: Shared<[f64; 2], Tensor<2>> = Arc::from(std::mem::replace(
        &mut p.diffusion,
        Box::new(|_| [[0.0; 2]; 2]),
    ));
    let a = logged("A", a, tensor_sum, &mut logs);
    p.diffusion = Box::new(move |x| a(x));
    scalar_field("f", &mut p.source, &mut logs);
    scalar_field("Dirichlet", &mut p.dirichlet, &mut logs);
    scalar_field("Neumann", &mut p.neumann, &mut logs);
    if let Some(f) = p.source_in_cell.take() {
        let g: Shared<([f64; 2], [f64; 2]), f64> = Arc::new(move |(x, xk)| f(x, xk));
        let w = logged("f in cell", g, identity, &mut logs);
        p.source_in_cell = Some(Box::new(move |x, xk| w((x, xk))));
    }
    if let Some(f) = p.diffusion_by_tag.take() {
        let g: Shared<([f64; 2], i32), Tensor<2>> = Arc::new(move |(x, t)| f(x, t));
        let w = logged("A by tag", g, tensor_sum, &mut logs);
        p.diffusion_by_tag = Some(Box::new(move |x, t| w((x, t))));
    }
    if let Some(f) = p.source_by_tag.take() {
        let g: Shared<([f64; 2], [f64; 2], i32), f64> = Arc::new(move |(x, xk, t)| f(x, xk, t));
        let w = logged("f by tag", g, identity, &mut logs);
        p.source_by_tag = Some(Box::new(move |x, xk, t| w((x, xk, t))));
    }
    let b = std::mem::replace(&mut p.boundary, Box::new(|_, _| BoundaryKind::Dirichlet));
    let g: Shared<([f64; 2], i32), BoundaryKind> = Arc::new(move |(x, t)| b(x, t));
    let w = logged("boundary kind", g, kind, &mut logs);
    p.boundary = Box::new(move |x, t| w((x, t)));
    if let Some(c) = &mut p.constraint {
        scalar_field("barrier", &mut c.barrier, &mut logs);
    }
    if let Some(e) = &mut p.exact {
        scalar_field("exact u", &mut e.u, &mut logs);
        let g: Shared<[f64; 2], [f64; 2]> =
            Arc::from(std::mem::replace(&mut e.grad, placeholder()));
        let w = logged("exact gradient", g, vector_sum, &mut logs);
        e.grad = Box::new(move |x| w(x));
    }
    (problem, logs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use gradvi::problem::paper_test3;

    #[test]
    fn a_recorded_problem_gives_the_same_values_and_logs_every_call() {
        let reference = paper_test3(-5.0);
        let (p, logs) = record(paper_test3(-5.0));
        let pts = [[0.1, 0.2], [0.5, 0.5], [0.9, 0.3]];
        for x in pts {
            assert_eq!((p.source)(x).to_bits(), (reference.source)(x).to_bits());
            assert_eq!(
                (p.dirichlet)(x).to_bits(),
                (reference.dirichlet)(x).to_bits()
            );
            assert_eq!((p.diffusion)(x), (reference.diffusion)(x));
            assert_eq!((p.boundary)(x, 0), (reference.boundary)(x, 0));
        }
        let barrier = p.constraint.as_ref().map(|c| (c.barrier)([0.3, 0.3]));
        let expected = reference
            .constraint
            .as_ref()
            .map(|c| (c.barrier)([0.3, 0.3]));
        assert_eq!(barrier.map(f64::to_bits), expected.map(f64::to_bits));
        // 3 points × 4 data, and one barrier call
        let r = logs.replay_seconds();
        assert_eq!(r.evaluations, 12 + usize::from(barrier.is_some()));
        assert!(r.seconds >= 0.0);
        // a replay logs nothing more
        assert_eq!(logs.replay_seconds().evaluations, r.evaluations);
    }
}
