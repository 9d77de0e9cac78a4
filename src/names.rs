//! One name table per settings enum. Each value's name is the word the command line
//! takes, the word `Display` prints (reports, image metadata, `ember info`) and the
//! word `FromStr` reads back, so a name is typed once, here beside its enum, and a
//! value recorded in an image's metadata can be passed straight back as a flag.

use std::fmt;

/// A settings enum whose values each have one name and a one-line description.
pub trait Named: Copy + PartialEq + Sized + 'static {
    /// What the values name, for error messages ("BVH builder").
    const WHAT: &'static str;
    /// Every value with its name and description, in the order help lists them.
    const TABLE: &'static [(Self, &'static str, &'static str)];

    /// The value's name.
    fn name(self) -> &'static str {
        Self::TABLE
            .iter()
            .find(|(v, _, _)| *v == self)
            .map(|(_, n, _)| *n)
            // Every value has a row: `tables_are_complete` below checks each type.
            .unwrap_or("?")
    }

    /// The value named `s` (ASCII case ignored).
    fn from_name(s: &str) -> Result<Self, UnknownName> {
        Self::TABLE
            .iter()
            .find(|(_, n, _)| n.eq_ignore_ascii_case(s))
            .map(|(v, _, _)| *v)
            .ok_or_else(|| UnknownName {
                what: Self::WHAT,
                got: s.to_string(),
                expected: Self::TABLE.iter().map(|(_, n, _)| *n).collect(),
            })
    }
}

/// A name that is in no row of the table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownName {
    pub what: &'static str,
    pub got: String,
    pub expected: Vec<&'static str>,
}

impl fmt::Display for UnknownName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown {} {:?} (expected one of: {})",
            self.what,
            self.got,
            self.expected.join(", ")
        )
    }
}

impl std::error::Error for UnknownName {}

/// `Display` and `FromStr` of a [`Named`] type, from its table.
macro_rules! display_from_table {
    ($t:ty) => {
        impl std::fmt::Display for $t {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str($crate::names::Named::name(*self))
            }
        }

        impl std::str::FromStr for $t {
            type Err = $crate::names::UnknownName;
            fn from_str(s: &str) -> Result<Self, Self::Err> {
                <$t as $crate::names::Named>::from_name(s)
            }
        }
    };
}
pub(crate) use display_from_table;

/// "1 thread", "2 threads": for sentences that say how many threads ran.
pub fn thread_count(n: usize) -> String {
    match n {
        1 => "1 thread".into(),
        n => format!("{n} threads"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{Backend, BvhBuilder, EmbreeQuality};
    use crate::integrators::DirectStrategy;
    use crate::render::Shading;

    /// Every value has exactly one row, names are distinct, and they round-trip.
    fn check<T: Named + fmt::Debug + fmt::Display + std::str::FromStr>(all: &[T])
    where
        T::Err: fmt::Debug,
    {
        assert_eq!(T::TABLE.len(), all.len(), "{}", T::WHAT);
        for &v in all {
            assert_eq!(T::TABLE.iter().filter(|r| r.0 == v).count(), 1, "{v:?}");
            let name = v.to_string();
            assert_ne!(name, "?");
            assert_eq!(name.parse::<T>().unwrap(), v);
            assert_eq!(name.to_uppercase().parse::<T>().unwrap(), v);
        }
    }

    #[test]
    fn tables_are_complete() {
        use DirectStrategy as D;
        check(&[
            Backend::Auto,
            Backend::Native,
            Backend::Embree,
            Backend::None,
        ]);
        check(&[BvhBuilder::Sah, BvhBuilder::Midpoint]);
        check(&[
            EmbreeQuality::Low,
            EmbreeQuality::Medium,
            EmbreeQuality::High,
        ]);
        check(&[Shading::Radiance, Shading::Normals, Shading::BvhCost]);
        check(&[D::Light, D::Mis, D::MisGlossy, D::Hemisphere, D::Bsdf]);
    }

    #[test]
    fn unknown_name_lists_the_choices() {
        let e = "octree".parse::<BvhBuilder>().unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown BVH builder \"octree\" (expected one of: sah, midpoint)"
        );
    }
}
