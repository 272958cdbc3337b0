//! The schema: what a problem file may contain, as serde types (unknown keys are rejected
//! everywhere), with the spans of the values for error positions.

use crate::scheme::SchemeKind;
use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use std::collections::BTreeMap;
use std::fmt;
use toml::Spanned;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFile {
    pub(super) name: Option<Spanned<String>>,
    pub(super) description: Option<String>,
    pub(super) scheme: Option<SchemeKind>,
    pub(super) mesh: Option<Spanned<RawMesh>>,
    #[serde(default)]
    pub(super) parameters: BTreeMap<String, Spanned<f64>>,
    #[serde(default)]
    pub(super) definitions: BTreeMap<String, Spanned<Src>>,
    pub(super) diffusion: Option<Spanned<RawDiffusion>>,
    pub(super) source: Option<Spanned<RawSource>>,
    pub(super) dirichlet: Option<RawDirichlet>,
    pub(super) neumann: Option<RawNeumann>,
    pub(super) signorini: Option<RawSignorini>,
    pub(super) obstacle: Option<RawObstacle>,
    pub(super) exact: Option<RawExact>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMesh {
    pub(super) file: Option<String>,
    pub(super) generate: Option<String>,
    pub(super) level: Option<usize>,
    /// \[x0, x1, y0, y1\] for a 2D family, \[x0, x1, y0, y1, z0, z1\] for a 3D one.
    pub(super) domain: Option<Vec<f64>>,
}

/// A datum given whole (`KEY = ...`) or by pieces (`[[SECTION.piece]]`, each with `where`,
/// `tags` and `KEY`): the section's struct, its piece's struct, and their [`Piecewise`] view.
macro_rules! piecewise_section {
    ($section:ident, $piece:ident, $name:literal, $key:literal, $ty:ty) => {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        pub(super) struct $section {
            #[serde(rename = $key)]
            value: Option<Spanned<$ty>>,
            piece: Option<Vec<$piece>>,
        }

        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        pub(super) struct $piece {
            #[serde(rename = "where")]
            cond: Option<Spanned<Src>>,
            tags: Option<Spanned<Vec<i32>>>,
            #[serde(rename = $key)]
            value: Spanned<$ty>,
        }

        impl Piecewise for $section {
            type Value = $ty;
            const SECTION: &'static str = $name;
            const KEY: &'static str = $key;
            fn whole(&self) -> Option<&Spanned<$ty>> {
                self.value.as_ref()
            }
            fn pieces(&self) -> Option<Vec<PieceSrc<'_, $ty>>> {
                let pieces = self.piece.as_ref()?;
                Some(
                    pieces
                        .iter()
                        .map(|p| (&p.cond, &p.tags, &p.value))
                        .collect(),
                )
            }
        }
    };
}

/// One piece as written: its condition (`where`), its cell tags and its value.
pub(super) type PieceSrc<'a, T> = (
    &'a Option<Spanned<Src>>,
    &'a Option<Spanned<Vec<i32>>>,
    &'a Spanned<T>,
);

/// A piecewise datum as written (made by `piecewise_section!`).
pub(super) trait Piecewise {
    /// The value as written (an expression, or a tensor).
    type Value;
    /// The section ("diffusion").
    const SECTION: &'static str;
    /// The key of the value ("A").
    const KEY: &'static str;
    /// The value, if given whole.
    fn whole(&self) -> Option<&Spanned<Self::Value>>;
    /// The pieces, if given by pieces.
    fn pieces(&self) -> Option<Vec<PieceSrc<'_, Self::Value>>>;
}

piecewise_section!(RawDiffusion, RawDiffusionPiece, "diffusion", "A", TensorSrc);
piecewise_section!(RawSource, RawSourcePiece, "source", "f", Src);

/// A boundary section: the edges it selects (`tags`, `where`), then its own keys.
macro_rules! boundary_section {
    ($name:ident { $($key:ident: $ty:ty),* }) => {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        pub(super) struct $name {
            pub(super) tags: Option<Spanned<Vec<i32>>>,
            #[serde(rename = "where")]
            pub(super) cond: Option<Spanned<Src>>,
            $(pub(super) $key: $ty,)*
        }
    };
}

boundary_section!(RawDirichlet { value: Option<Spanned<Src>> });
boundary_section!(RawNeumann { flux: Option<Spanned<Src>> });
boundary_section!(RawSignorini { side: RawSide, barrier: Spanned<Src> });

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawObstacle {
    pub(super) side: RawSide,
    pub(super) barrier: Spanned<Src>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawExact {
    pub(super) u: Spanned<Src>,
    /// D components on a D-dimensional mesh (checked when compiling for D).
    pub(super) grad: Spanned<Vec<Spanned<Src>>>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
pub(super) enum RawSide {
    Upper,
    Lower,
}

/// An expression as written: a TOML number or a string.
#[derive(Debug, Clone)]
pub(super) enum Src {
    Number(f64),
    Text(String),
}

struct SrcVisitor;

impl Visitor<'_> for SrcVisitor {
    type Value = Src;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number or an expression in a string")
    }
    fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<Src, E> {
        Ok(Src::Text(v.to_string()))
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Src, E> {
        Ok(Src::Number(v))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Src, E> {
        Ok(Src::Number(v as f64))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Src, E> {
        Ok(Src::Number(v as f64))
    }
}

impl<'de> Deserialize<'de> for Src {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        d.deserialize_any(SrcVisitor)
    }
}

/// A diffusion coefficient as written: a scalar a (A = a I), or a square array of size 2 or 3
/// (rows of entries; the size must be the mesh's dimension, checked when compiling for it).
pub(super) enum TensorSrc {
    Scalar(Src),
    Matrix(Vec<Vec<Spanned<Src>>>),
}

struct TensorVisitor;

impl<'de> Visitor<'de> for TensorVisitor {
    type Value = TensorSrc;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(
            "a number, an expression in a string, or a 2x2 array [[a11, a12], [a21, a22]] \
             (2D) or a 3x3 array (3D)",
        )
    }
    fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<TensorSrc, E> {
        SrcVisitor.visit_str(v).map(TensorSrc::Scalar)
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<TensorSrc, E> {
        SrcVisitor.visit_f64(v).map(TensorSrc::Scalar)
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<TensorSrc, E> {
        SrcVisitor.visit_i64(v).map(TensorSrc::Scalar)
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<TensorSrc, E> {
        SrcVisitor.visit_u64(v).map(TensorSrc::Scalar)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<TensorSrc, A::Error> {
        let mut rows: Vec<Vec<Spanned<Src>>> = Vec::new();
        while let Some(row) = seq.next_element::<Vec<Spanned<Src>>>()? {
            if rows.len() == 3 {
                return Err(de::Error::invalid_length(4, &self));
            }
            rows.push(row);
        }
        let n = rows.len();
        if n < 2 {
            return Err(de::Error::invalid_length(n, &self));
        }
        if let Some(row) = rows.iter().find(|r| r.len() != n) {
            let what = format!("rows of length {n} (a square array)");
            return Err(de::Error::invalid_length(row.len(), &what.as_str()));
        }
        Ok(TensorSrc::Matrix(rows))
    }
}

impl<'de> Deserialize<'de> for TensorSrc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        d.deserialize_any(TensorVisitor)
    }
}

#[cfg(test)]
mod tests {
    use super::{RawFile, Src, TensorSrc};
    use serde::Deserialize;

    #[derive(Deserialize)]
    struct One<T> {
        v: T,
    }

    fn value<T: for<'de> Deserialize<'de>>(toml: &str) -> Result<T, toml::de::Error> {
        toml::from_str::<One<T>>(&format!("v = {toml}")).map(|o| o.v)
    }

    #[test]
    fn expressions_are_numbers_or_strings() {
        assert!(matches!(value::<Src>("2"), Ok(Src::Number(2.0))));
        assert!(matches!(value::<Src>("-2.5e-1"), Ok(Src::Number(-0.25))));
        assert!(matches!(value::<Src>("\"x + 1\""), Ok(Src::Text(t)) if t == "x + 1"));
        let e = value::<Src>("true").err().unwrap();
        assert!(
            e.message()
                .contains("a number or an expression in a string"),
            "{e}"
        );
    }

    #[test]
    fn tensors_are_scalars_or_square_arrays_of_size_two_or_three() {
        assert!(matches!(
            value::<TensorSrc>("3"),
            Ok(TensorSrc::Scalar(Src::Number(3.0)))
        ));
        let Ok(TensorSrc::Matrix(m)) = value::<TensorSrc>("[[1, \"x\"], [\"x\", 4]]") else {
            panic!("a 2x2 array is a matrix");
        };
        assert!(matches!(m[0][1].get_ref(), Src::Text(t) if t == "x"));
        assert!(matches!(m[1][1].get_ref(), Src::Number(4.0)));
        let Ok(TensorSrc::Matrix(m)) = value::<TensorSrc>("[[1, 0, 0], [0, 1, 0], [0, 0, \"z\"]]")
        else {
            panic!("a 3x3 array is a matrix");
        };
        assert!(m.len() == 3 && matches!(m[2][2].get_ref(), Src::Text(t) if t == "z"));
        for bad in [
            "[[1, 0]]",
            "[[1, 0], [0, 1], [0, 0]]",
            "[[1], [0, 1]]",
            "[[1, 0, 0], [0, 1, 0]]",
            "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]",
        ] {
            let e = value::<TensorSrc>(bad).err().unwrap();
            assert!(e.message().contains("invalid length"), "{bad}: {e}");
        }
    }

    #[test]
    fn domains_gradients_and_tensors_are_read_whatever_their_dimension() {
        let domain = |d: &str| toml::from_str::<RawFile>(&format!("[mesh]\ndomain = {d}"));
        let Ok(RawFile { mesh: Some(m), .. }) = domain("[0, 1, -2, 2]") else {
            panic!("a domain of four values is read");
        };
        // its length is checked against the family's dimension when the mesh is compiled
        assert_eq!(m.get_ref().domain, Some(vec![0.0, 1.0, -2.0, 2.0]));
        let grad = |g: &str| toml::from_str::<RawFile>(&format!("[exact]\nu = 0\ngrad = {g}"));
        assert!(grad("[\"y\", \"x\"]").is_ok());
        assert!(grad("[\"y\", \"x\", \"z\"]").is_ok());
        let e = value::<TensorSrc>("[[1, 0, 7], [0, 1]]").err().unwrap();
        assert_eq!(
            e.message(),
            "invalid length 3, expected rows of length 2 (a square array)"
        );
    }

    #[test]
    fn unknown_keys_are_rejected_everywhere() {
        assert!(toml::from_str::<RawFile>("[source]\nf = 1\n").is_ok());
        for bad in [
            "colour = 1",
            "[source]\nf = 1\ng = 2",
            "[[source.piece]]\nf = 1\nwhen = \"x < 1\"",
            "[dirichlet]\nvalue = 0\nflux = 1",
            "[mesh]\nfile = \"m.msh\"\nlevels = 2",
        ] {
            let e = toml::from_str::<RawFile>(bad).err().unwrap();
            assert!(e.message().starts_with("unknown field"), "{bad}: {e}");
        }
    }
}
