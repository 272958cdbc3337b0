//! [`FixedValues`]: the values of some unknowns of a system (the Dirichlet ones, or those an
//! active set fixes at their barriers), the others free.

use crate::budget::{AllocFailure, try_filled};

/// The value of each fixed unknown of a system of order n, the other unknowns free: 8 bytes
/// per unknown (a free unknown is stored as NaN, which no fixed value can be: the data and the
/// barriers are checked finite before they fix anything), where a vector of `Option<f64>`
/// takes 16. A solve of n unknowns holds two (the Dirichlet values and the values an active
/// set fixes), so this saves 16 bytes per unknown at the peak of every solve.
#[derive(Debug, Clone, PartialEq)]
pub struct FixedValues {
    /// The value of unknown i, NaN if it is free.
    values: Vec<f64>,
}

impl FixedValues {
    /// `n` free unknowns, or [`AllocFailure`] if the array cannot be had.
    pub fn free(n: usize) -> Result<Self, AllocFailure> {
        Ok(FixedValues {
            values: try_filled(n, f64::NAN, "the values of the fixed unknowns")?,
        })
    }

    /// The unknowns of `values` in order: `Some(v)` fixed at v, `None` free. A non-finite
    /// `v` is an error naming its unknown. (The array grows as `values` comes, infallibly: for
    /// the small systems of tests and examples; a solve builds its values with [`Self::free`].)
    pub fn from_options(values: impl IntoIterator<Item = Option<f64>>) -> crate::Result<Self> {
        let mut out = Vec::new();
        for (i, v) in values.into_iter().enumerate() {
            match v {
                Some(v) if !v.is_finite() => return Err(non_finite(i, v)),
                Some(v) => out.push(v),
                None => out.push(f64::NAN),
            }
        }
        Ok(FixedValues { values: out })
    }

    /// The number of unknowns (fixed or free).
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// No unknowns.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The value of unknown `i` if it is fixed, `None` if it is free.
    #[inline]
    pub fn get(&self, i: usize) -> Option<f64> {
        let v = self.values[i];
        if v.is_nan() { None } else { Some(v) }
    }

    /// Whether unknown `i` is fixed.
    #[inline]
    pub fn is_fixed(&self, i: usize) -> bool {
        !self.values[i].is_nan()
    }

    /// Fixes unknown `i` at the finite value `v`; a non-finite `v` is an error (it would read
    /// as free, or fix the unknown at an infinite value).
    pub fn try_set(&mut self, i: usize, v: f64) -> crate::Result<()> {
        if !v.is_finite() {
            return Err(non_finite(i, v));
        }
        self.values[i] = v;
        Ok(())
    }

    /// Fixes unknown `i` at `v`, which the caller has checked finite (the Dirichlet data and the
    /// barriers are checked where they are evaluated).
    #[inline]
    pub(crate) fn set(&mut self, i: usize, v: f64) {
        debug_assert!(v.is_finite(), "unknown {i} fixed at {v}");
        self.values[i] = v;
    }

    /// The unknowns in order: `Some(v)` fixed at v, `None` free.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = Option<f64>> + '_ {
        self.values
            .iter()
            .map(|&v| if v.is_nan() { None } else { Some(v) })
    }
}

/// The error of fixing unknown `i` at the non-finite value `v`.
fn non_finite(i: usize, v: f64) -> crate::Error {
    crate::Error::InvalidData(format!(
        "unknown {i} cannot be fixed at the non-finite value {v}"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_and_free_unknowns_read_back_as_options() {
        let f = FixedValues::from_options([Some(1.5), None, Some(-0.0), Some(0.0), None]).unwrap();
        assert_eq!(f.len(), 5);
        assert_eq!(
            f.iter().collect::<Vec<_>>(),
            [Some(1.5), None, Some(-0.0), Some(0.0), None]
        );
        assert!(f.is_fixed(2) && !f.is_fixed(4));
        assert_eq!(f.get(0), Some(1.5));
        let mut g = FixedValues::free(3).unwrap();
        assert!(g.iter().all(|v| v.is_none()));
        g.try_set(1, 2.0).unwrap();
        assert_eq!(g.iter().collect::<Vec<_>>(), [None, Some(2.0), None]);
        // a value that is not finite is refused, naming the unknown, and changes nothing
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let e = g.try_set(2, v).unwrap_err().to_string();
            assert!(e.contains("unknown 2") && e.contains("non-finite"), "{e}");
            assert_eq!(g.get(2), None);
        }
        for v in [f64::NAN, f64::INFINITY] {
            let e = FixedValues::from_options([None, Some(v)])
                .unwrap_err()
                .to_string();
            assert!(e.contains("unknown 1"), "{e}");
        }
    }
}
