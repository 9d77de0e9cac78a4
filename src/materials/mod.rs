//! Materials (spec §6): a BSDF and, optionally, emission. Each BSDF kind is a small
//! unit, in its own file, whose `eval`, `sample` and `pdf` agree; it is written once
//! over the lane type (`Scatter<F>`), so one path and sixteen run the same code.
//! Directions are in the local shading frame (+z = shading normal), `wo` toward the
//! eye, `wi` toward the light.
//!
//! Adding a BSDF kind: write its file (its parameters as a struct generic over the
//! float type, implementing [`Scatter`]) and add one line to the `bsdfs!` list
//! below. Every integrator reaches BSDFs only through [`Bsdf`] and [`BsdfLanes`],
//! which the list generates, so nothing else needs to know the kind exists; a kind
//! that does not implement all of `Scatter` does not compile.

pub mod fresnel;
pub mod lambertian;
pub mod microfacet;
pub mod specular;

use crate::lanes::{each_lane, LaneBits, LaneMask, Lanes, Real, LANES, V3};
use crate::Color;
use glam::{Vec2, Vec3};
pub use lambertian::Lambertian;
pub use microfacet::Conductor;
pub use specular::{Glass, Mirror, Refraction};
use std::fmt;

/// What kind of scattering a BSDF has, as pbrt-v4's `BxDFFlags`: the integrators ask
/// these instead of matching on kinds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BsdfFlags {
    /// Every lobe is a delta distribution: light sampling is pointless there.
    pub delta: bool,
    /// A non-delta lobe narrow enough that BSDF sampling beats light sampling on it.
    pub glossy: bool,
    /// A broad non-delta lobe.
    pub diffuse: bool,
    /// `sample` reads its `u_lobe` (a choice between lobes): the integrators draw
    /// that number only for lanes whose BSDF does.
    pub chooses_lobe: bool,
}

impl BsdfFlags {
    pub const NONE: BsdfFlags = BsdfFlags {
        delta: false,
        glossy: false,
        diffuse: false,
        chooses_lobe: false,
    };
    pub const DELTA: BsdfFlags = BsdfFlags {
        delta: true,
        ..Self::NONE
    };
    pub const GLOSSY: BsdfFlags = BsdfFlags {
        glossy: true,
        ..Self::NONE
    };
    pub const DIFFUSE: BsdfFlags = BsdfFlags {
        diffuse: true,
        ..Self::NONE
    };

    /// Whether anything is scattered.
    pub fn scatters(&self) -> bool {
        self.delta || self.glossy || self.diffuse
    }
}

/// A direction drawn by `Scatter::sample`, per lane.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample<F: Real> {
    /// Local incident direction (unit).
    pub wi: V3<F>,
    /// The estimator weight `f·|cos θi| / pdf`; for a delta lobe, the lobe's factor
    /// (e.g. `F·R` for glass reflection) divided by the probability of choosing it.
    pub weight: V3<F>,
    /// Solid-angle pdf of `wi`; for a delta lobe, the probability of choosing that lobe.
    pub pdf: F,
    /// Lanes that drew a direction (the rest scatter nothing: zero density, total
    /// internal reflection of `Refraction`, invalid parameters).
    pub valid: F::M,
}

/// One BSDF kind, over a lane type `F`: its parameters (one value per lane) and its
/// scattering. `eval` and `pdf` default to zero, as for delta lobes.
pub trait Scatter<F: Real>: Copy {
    /// The parameters for one path (`Self` at `f32`).
    type One: Copy + fmt::Debug + PartialEq;
    const FLAGS: BsdfFlags;
    /// The lanes' parameters from each lane's own (`each[i]` for lane `i`).
    fn gather<L: Lanes<F = F>>(l: L, each: &F::Array<Self::One>) -> Self;
    /// `f(wo, wi)` without the cosine.
    #[inline(always)]
    fn eval(&self, wo: V3<F>, _wi: V3<F>) -> V3<F> {
        let zero = wo.x.splat_as(0.0);
        V3::new(zero, zero, zero)
    }
    /// Solid-angle density with which `sample` returns `wi`.
    #[inline(always)]
    fn pdf(&self, wo: V3<F>, _wi: V3<F>) -> F {
        wo.x.splat_as(0.0)
    }
    /// Draws `wi` given `wo`: `u_lobe` chooses a lobe, `u` the direction.
    fn sample(&self, wo: V3<F>, u_lobe: F, u: (F, F)) -> BsdfSample<F>;
    /// The kind and its parameters, for `ember info`: `lambertian: albedo (0.5, 0.5, 0.5)`.
    fn describe(one: &Self::One) -> String;
    /// Whether this BSDF focuses light into caustics that path tracing finds only by
    /// chance: delta lobes, and glossy lobes narrow enough to act like them
    /// (`Estimator::Caustics` light-traces the paths that reach a light through one).
    fn focuses(_one: &Self::One) -> bool {
        Self::FLAGS.delta
    }
    /// The factor by which radiance (not importance) is scaled along `wo ← wi`:
    /// `(ηi/ηt)²` across a refracting interface, else 1 (for adjoint transport).
    #[inline(always)]
    fn radiance_scale(&self, wo: V3<F>, _wi: V3<F>) -> F {
        wo.x.splat_as(1.0)
    }
}

/// Scatters nothing: the surface of an area light (whose light gives its radiance),
/// and pure emitters.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct NonScattering<F = f32> {
    lanes: std::marker::PhantomData<F>,
}

impl<F: Real> Scatter<F> for NonScattering<F> {
    type One = NonScattering;
    const FLAGS: BsdfFlags = BsdfFlags::NONE;
    #[inline(always)]
    fn gather<L: Lanes<F = F>>(_: L, _: &F::Array<NonScattering>) -> Self {
        NonScattering {
            lanes: std::marker::PhantomData,
        }
    }
    fn describe(_: &NonScattering) -> String {
        "non-scattering".into()
    }
    #[inline(always)]
    fn sample(&self, wo: V3<F>, _: F, _: (F, F)) -> BsdfSample<F> {
        let zero = wo.x.splat_as(0.0);
        BsdfSample {
            wi: wo,
            weight: V3::new(zero, zero, zero),
            pdf: zero,
            valid: zero.lt(zero),
        }
    }
}

/// Each lane's value of a colour parameter.
#[inline(always)]
pub fn gather_v3<L: Lanes, T: Copy>(
    l: L,
    each: &<L::F as Real>::Array<T>,
    f: impl Fn(&T) -> V3<f32>,
) -> V3<L::F> {
    let mut a = [[0.0f32; LANES]; 3];
    for i in 0..L::WIDTH {
        let v = f(&each[i]);
        (a[0][i], a[1][i], a[2][i]) = (v.x, v.y, v.z);
    }
    V3::from_arrays(l, &a)
}

/// Each lane's value of a scalar parameter.
#[inline(always)]
pub fn gather_f<L: Lanes, T: Copy>(
    l: L,
    each: &<L::F as Real>::Array<T>,
    f: impl Fn(&T) -> f32,
) -> L::F {
    let mut a = [0.0f32; LANES];
    for (i, v) in a.iter_mut().enumerate().take(L::WIDTH) {
        *v = f(&each[i]);
    }
    l.f_from(a)
}

/// Generates [`Bsdf`] (one path's BSDF, one variant per kind) and [`BsdfLanes`] (the
/// BSDFs of sixteen lanes, each kind present gathered once) from the list of kinds.
macro_rules! bsdfs {
    ($($(#[$doc:meta])* $kind:ident($ty:ident) = $name:literal,)*) => {
        /// A BSDF: one of the kinds.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum Bsdf {
            $($(#[$doc])* $kind($ty),)*
        }

        /// The kinds, numbered.
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        #[allow(clippy::enum_variant_names)]
        enum Kind { $($kind,)* }

        const KINDS: usize = [$(Kind::$kind,)*].len();

        impl Bsdf {
            fn kind(&self) -> Kind {
                match self { $(Bsdf::$kind(_) => Kind::$kind,)* }
            }

            /// What kind of scattering this BSDF has.
            pub fn flags(&self) -> BsdfFlags {
                match self { $(Bsdf::$kind(_) => <$ty as Scatter<f32>>::FLAGS,)* }
            }

            /// Whether this BSDF focuses light into caustics (`Scatter::focuses`).
            pub fn focuses(&self) -> bool {
                match self { $(Bsdf::$kind(b) => <$ty as Scatter<f32>>::focuses(b),)* }
            }

            /// The kind's name, as the loader and `ember info` say it.
            pub fn name(&self) -> &'static str {
                match self { $(Bsdf::$kind(_) => $name,)* }
            }

            /// The kind and its parameters.
            pub fn describe(&self) -> String {
                match self { $(Bsdf::$kind(b) => <$ty as Scatter<f32>>::describe(b),)* }
            }
        }

        /// The BSDFs of a set of lanes: each kind present, gathered once, with its lanes.
        #[allow(non_snake_case)]
        pub struct BsdfLanes<L: Lanes> {
            $($kind: Option<($ty<L::F>, L::M)>,)*
            /// Lanes whose BSDF is a delta distribution, and that scatter at all.
            pub delta: LaneBits,
            pub scattering: LaneBits,
            pub glossy: LaneBits,
            /// Lanes whose BSDF focuses light into caustics (`Scatter::focuses`).
            pub focus: LaneBits,
            /// Lanes whose BSDF reads `u_lobe` (`BsdfFlags::chooses_lobe`).
            pub chooses_lobe: LaneBits,
        }

        impl<L: Lanes> BsdfLanes<L> {
            /// The BSDF of each lane in `lanes`, `bsdf(i)` for lane `i`.
            #[inline(always)]
            pub fn gather(l: L, lanes: LaneBits, bsdf: impl Fn(usize) -> Bsdf) -> Self {
                let mut of_kind = [0 as LaneBits; KINDS];
                let mut first = [usize::MAX; KINDS];
                let mut all = <L::F as Real>::array_of(None);
                for i in each_lane(lanes) {
                    let b = bsdf(i);
                    let k = b.kind() as usize;
                    of_kind[k] |= 1 << i;
                    if first[k] == usize::MAX {
                        first[k] = i;
                    }
                    all[i] = Some(b);
                }
                let (mut delta, mut scattering, mut glossy, mut focus) = (0, 0, 0, 0);
                let mut chooses_lobe = 0;
                $(#[allow(non_snake_case)] let $kind = {
                    let k = Kind::$kind as usize;
                    if of_kind[k] != 0 {
                        let Some(Bsdf::$kind(fill)) = all[first[k]] else { unreachable!() };
                        let mut each = <L::F as Real>::array_of(fill);
                        for i in each_lane(of_kind[k]) {
                            if let Some(Bsdf::$kind(b)) = all[i] {
                                each[i] = b;
                                if <$ty as Scatter<f32>>::focuses(&b) { focus |= 1 << i; }
                            }
                        }
                        let flags = <$ty as Scatter<f32>>::FLAGS;
                        if flags.delta { delta |= of_kind[k]; }
                        if flags.chooses_lobe { chooses_lobe |= of_kind[k]; }
                        if flags.glossy { glossy |= of_kind[k]; }
                        if flags.scatters() { scattering |= of_kind[k]; }
                        Some((<$ty<L::F> as Scatter<L::F>>::gather(l, &each), l.mask(of_kind[k])))
                    } else {
                        None
                    }
                };)*
                BsdfLanes { $($kind,)* delta, scattering, glossy, focus, chooses_lobe }
            }

            /// `f(wo, wi)` of each lane's BSDF.
            #[inline(always)]
            pub fn eval(&self, l: L, wo: V3<L::F>, wi: V3<L::F>) -> V3<L::F> {
                let mut f = V3::splat(l, Vec3::ZERO);
                $(if let Some((b, m)) = &self.$kind {
                    f = V3::select(*m, b.eval(wo, wi), f);
                })*
                f
            }

            /// The solid-angle pdf of `wi` for each lane's BSDF.
            #[inline(always)]
            pub fn pdf(&self, l: L, wo: V3<L::F>, wi: V3<L::F>) -> L::F {
                let mut p = l.f(0.0);
                $(if let Some((b, m)) = &self.$kind {
                    p = L::F::select(*m, b.pdf(wo, wi), p);
                })*
                p
            }

            /// A direction drawn from each lane's BSDF.
            #[inline(always)]
            pub fn sample(&self, l: L, wo: V3<L::F>, u_lobe: L::F, u: (L::F, L::F)) -> BsdfSample<L::F> {
                let zero = l.f(0.0);
                let mut s = BsdfSample {
                    wi: wo,
                    weight: V3::splat(l, Vec3::ZERO),
                    pdf: zero,
                    valid: l.mask(0),
                };
                $(if let Some((b, m)) = &self.$kind {
                    let t = b.sample(wo, u_lobe, u);
                    s = BsdfSample {
                        wi: V3::select(*m, t.wi, s.wi),
                        weight: V3::select(*m, t.weight, s.weight),
                        pdf: L::F::select(*m, t.pdf, s.pdf),
                        valid: (*m & t.valid) | (!*m & s.valid),
                    };
                })*
                s
            }

            /// Each lane's radiance scale along `wo ← wi` (`Scatter::radiance_scale`).
            #[inline(always)]
            pub fn radiance_scale(&self, l: L, wo: V3<L::F>, wi: V3<L::F>) -> L::F {
                let mut k = l.f(1.0);
                $(if let Some((b, m)) = &self.$kind {
                    k = L::F::select(*m, b.radiance_scale(wo, wi), k);
                })*
                k
            }
        }
    };
}

bsdfs! {
    /// Two-sided diffuse reflection.
    Lambertian(Lambertian) = "lambertian",
    /// Perfect specular reflection.
    Mirror(Mirror) = "mirror",
    /// Smooth dielectric: index `ior` on the back (−z) side, 1 on the front.
    Glass(Glass) = "glass",
    /// Glass without its reflection.
    Refraction(Refraction) = "refraction",
    /// Rough conductor: Beckmann NDF, separable Smith G, exact conductor Fresnel.
    Microfacet(Conductor) = "microfacet",
    /// Scatters nothing (light surfaces, pure emitters).
    NonScattering(NonScattering) = "non-scattering",
}

/// A surface's material: how it scatters and what it emits itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub bsdf: Bsdf,
    /// Radiance emitted from the front side (both sides when `two_sided`), in
    /// addition to what is scattered. Area lights' surfaces take theirs from the light.
    pub emission: Color,
    pub two_sided: bool,
}

impl Default for Material {
    fn default() -> Self {
        Material::lambertian(Color::splat(0.5))
    }
}

impl From<Bsdf> for Material {
    fn from(bsdf: Bsdf) -> Self {
        Material {
            bsdf,
            emission: Color::ZERO,
            two_sided: false,
        }
    }
}

/// A direction drawn by [`Material::sample`] (one path).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScatterSample {
    pub wi: Vec3,
    pub weight: Color,
    pub pdf: f32,
    /// True when `wi` came from a delta (specular) lobe.
    pub delta: bool,
}

impl Material {
    pub fn lambertian(albedo: Color) -> Self {
        Bsdf::Lambertian(Lambertian {
            albedo: albedo.into(),
        })
        .into()
    }

    pub fn mirror(reflectance: Color) -> Self {
        Bsdf::Mirror(Mirror {
            reflectance: reflectance.into(),
        })
        .into()
    }

    pub fn glass(ior: f32, reflectance: Color, transmittance: Color) -> Self {
        Bsdf::Glass(Glass {
            ior,
            reflectance: reflectance.into(),
            transmittance: transmittance.into(),
        })
        .into()
    }

    pub fn refraction(ior: f32, transmittance: Color) -> Self {
        Bsdf::Refraction(Refraction {
            ior,
            transmittance: transmittance.into(),
        })
        .into()
    }

    pub fn microfacet(alpha: f32, eta: Color, k: Color) -> Self {
        Bsdf::Microfacet(Conductor::new(alpha, eta, k)).into()
    }

    /// Emits `radiance` from its front side and scatters nothing (the course's
    /// `<emission>` material).
    pub fn emitter(radiance: Color) -> Self {
        Material {
            emission: radiance,
            ..Bsdf::NonScattering(NonScattering::default()).into()
        }
    }

    /// The surface of an area light: scatters nothing, and its radiance is the light's.
    pub fn light_surface() -> Self {
        Bsdf::NonScattering(NonScattering::default()).into()
    }

    /// This material also emitting `radiance` (from both sides when `two_sided`).
    pub fn with_emission(self, radiance: Color, two_sided: bool) -> Self {
        Material {
            emission: radiance,
            two_sided,
            ..self
        }
    }

    /// Whether the material emits light itself.
    pub fn emits(&self) -> bool {
        self.emission != Color::ZERO
    }

    pub fn flags(&self) -> BsdfFlags {
        self.bsdf.flags()
    }

    /// True when every lobe is a delta distribution (mirror, glass, refraction):
    /// light sampling is pointless there.
    pub fn is_delta(&self) -> bool {
        self.flags().delta
    }

    /// Whether the material focuses light into caustics (`Scatter::focuses`).
    pub fn focuses(&self) -> bool {
        self.bsdf.focuses()
    }

    /// Whether the material scatters light at all.
    pub fn scatters(&self) -> bool {
        self.flags().scatters()
    }

    /// Radiance emitted toward local direction `wo`.
    pub fn emitted(&self, wo: Vec3) -> Color {
        if wo.z > 0.0 || (self.two_sided && wo.z < 0.0) {
            self.emission
        } else {
            Color::ZERO
        }
    }

    /// The BSDF for one path.
    fn one(&self) -> BsdfLanes<crate::lanes::One> {
        BsdfLanes::gather(crate::lanes::One, 1, |_| self.bsdf)
    }

    /// `f(wo, wi)` without the cosine; zero for delta materials.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Color {
        self.one()
            .eval(crate::lanes::One, wo.into(), wi.into())
            .vec3()
    }

    /// Solid-angle density with which `sample` returns `wi`; zero for delta lobes.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.one().pdf(crate::lanes::One, wo.into(), wi.into())
    }

    /// Draws `wi` given `wo`. `u_lobe` chooses a lobe, `u` the direction. `None` when
    /// nothing scatters.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<ScatterSample> {
        let s = self
            .one()
            .sample(crate::lanes::One, wo.into(), u_lobe, (u.x, u.y));
        s.valid.any().then(|| ScatterSample {
            wi: s.wi.vec3(),
            weight: s.weight.vec3(),
            pdf: s.pdf,
            delta: self.is_delta(),
        })
    }

    /// The factor by which radiance is scaled along `wo ← wi` (`Scatter::radiance_scale`).
    pub fn radiance_scale(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.one()
            .radiance_scale(crate::lanes::One, wo.into(), wi.into())
    }

    /// The kind and every parameter, for `ember info`: `lambertian: albedo (0.5, 0.5, 0.5)`.
    pub fn describe(&self) -> String {
        let v = crate::color::compact;
        match (self.bsdf, self.emits()) {
            (Bsdf::NonScattering(_), true) => format!("{self}: radiance {}", v(self.emission)),
            (Bsdf::NonScattering(_), false) => "non-scattering (an area light's surface)".into(),
            (b, false) => b.describe(),
            (b, true) => {
                let sides = if self.two_sided {
                    "both sides"
                } else {
                    "front"
                };
                format!("{}; emits {} ({sides})", b.describe(), v(self.emission))
            }
        }
    }
}

/// The material's kind, as the loader and `ember info` name it.
impl fmt::Display for Material {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self.bsdf {
            Bsdf::NonScattering(_) if self.emits() => f.write_str("emission"),
            b => f.write_str(b.name()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec2, Vec3};

    /// A material of every kind (a new kind fails the test below until it is added).
    fn every_kind() -> Vec<Material> {
        let c = Color::new(0.9, 0.5, 0.2);
        vec![
            Material::lambertian(c),
            Material::mirror(c),
            Material::glass(1.5, c, c),
            Material::refraction(1.5, c),
            Material::microfacet(0.3, c, c),
            Material::light_surface(),
        ]
    }

    /// The integrators draw `u_lobe` only for BSDFs whose flags say they read it, so
    /// a BSDF that reads it without saying so would sample from a constant. Each kind
    /// is sampled with two lobe numbers at many points: only kinds that choose a lobe
    /// may differ, and those do (else the flag costs draws for nothing).
    #[test]
    fn only_bsdfs_that_choose_a_lobe_read_its_number() {
        let materials = every_kind();
        let kinds: std::collections::HashSet<_> =
            materials.iter().map(|m| m.bsdf.kind() as usize).collect();
        assert_eq!(kinds.len(), KINDS, "every_kind() must hold every kind");
        for m in materials {
            let mut differs = false;
            for i in 0..64 {
                let t = (i as f32 + 0.5) / 64.0;
                let wo = Vec3::new(0.6 * t, -0.3, 1.0 - t).normalize();
                let wo = if i % 2 == 0 { wo } else { -wo };
                let u = Vec2::new(t, (t * 7.31).fract());
                differs |= m.sample(wo, 0.02, u) != m.sample(wo, 0.98, u);
            }
            assert_eq!(differs, m.flags().chooses_lobe, "{}", m.bsdf.name());
        }
    }
}
