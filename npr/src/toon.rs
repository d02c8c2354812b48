//! `toon`: hard shading, the course notes' colour blocks at shading time.
//!
//! Per light of irradiance E arriving from wi (every light kind, lights.rs),
//! with n·l = n·wi:
//!
//! L = base/π ⊙ E ⊙ ramp(n·l)  +  [n·h ≥ specular_threshold ∧ n·l > 0] specular/π ⊙ E
//!
//! plus base ⊙ L_env under a uniform environment (the Lambert albedo), or
//! base ⊙ E(n)/π under an environment map (its SH irradiance), and
//! a rim term: rim_color (radiance) where 1 − n·v ≥ rim_threshold.
//! `ramp` is a step function of n·l: [`Ramp::bands`] gives n bands of
//! equal width in n·l, value (k + 1)/n on [k/n, (k + 1)/n) and 0 where
//! n·l ≤ 0; an explicit ramp gives colour c_i from edge e_i up to the next
//! edge, black below the first. base is `base_color`, times the
//! base-colour texture where there is one: the shader's lane parameters
//! (`ToonParams`) are filled by its maps the way a physically based
//! model's are (raster's maps.rs).

use crate::lights::for_each_light_shadowed;
use crate::ParamError;
use specula_core::{LaneParams, Real, Rgb};
use specula_raster::maps::ParamMaps;
use specula_raster::{PacketShader, ShadeEnv, ShadeInput};

/// A step function of n·l: (edge, RGB factor) pairs, edges increasing.
#[derive(Clone, Debug, PartialEq)]
pub struct Ramp {
    steps: Vec<(f32, [f32; 3])>,
    /// n·l ≤ 0 gives 0 whatever the steps say (bands).
    lit_only: bool,
}

impl Ramp {
    /// `n` bands of equal width over n·l ∈ (0, 1] (module docs).
    pub fn bands(n: u32) -> Result<Ramp, ParamError> {
        if !(1..=64).contains(&n) {
            return Err(ParamError::new(
                "bands",
                format!("must be in 1..=64, got {n}"),
            ));
        }
        Ok(Ramp {
            steps: (0..n)
                .map(|k| (k as f32 / n as f32, [(k + 1) as f32 / n as f32; 3]))
                .collect(),
            lit_only: true,
        })
    }

    /// An explicit ramp: colour `c_i` from `e_i` (in [−1, 1], strictly
    /// increasing) up to the next edge; black below the first.
    pub fn explicit(steps: Vec<(f32, [f32; 3])>) -> Result<Ramp, ParamError> {
        if steps.is_empty() || steps.len() > 64 {
            return Err(ParamError::new(
                "ramp",
                format!("needs 1 to 64 entries, got {}", steps.len()),
            ));
        }
        for (i, (e, c)) in steps.iter().enumerate() {
            if !(-1.0..=1.0).contains(e) {
                return Err(ParamError::new(
                    format!("ramp[{i}]"),
                    format!("edge must be in [-1, 1], got {e}"),
                ));
            }
            if i > 0 && *e <= steps[i - 1].0 {
                return Err(ParamError::new(
                    format!("ramp[{i}]"),
                    format!("edges must increase, got {e} after {}", steps[i - 1].0),
                ));
            }
            if !c.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(ParamError::new(
                    format!("ramp[{i}]"),
                    format!("colour components must be finite and ≥ 0, got {c:?}"),
                ));
            }
        }
        Ok(Ramp {
            steps,
            lit_only: false,
        })
    }

    /// The step value at `cos` per lane.
    #[inline(always)]
    pub(crate) fn eval<R: Real>(&self, cos: R) -> Rgb<R> {
        let mut v = Rgb::zero();
        for (edge, c) in &self.steps {
            v = Rgb::select(cos.ge(R::splat(*edge as f64)), Rgb::from_f32(*c), v);
        }
        if self.lit_only {
            v = Rgb::select(cos.gt(R::ZERO), v, Rgb::zero());
        }
        v
    }
}

/// A hard highlight or rim: where the test value reaches `threshold`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hard {
    pub threshold: f32,
    pub color: [f32; 3],
}

/// The toon shader's parameters per lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ToonParams<R: Real> {
    pub(crate) base_color: Rgb<R>,
}

impl<R: Real> LaneParams<R> for ToonParams<R> {
    #[inline(always)]
    fn base_color_mut(&mut self) -> Option<&mut Rgb<R>> {
        Some(&mut self.base_color)
    }
}

/// The `toon` shader; see the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct Toon {
    pub base_color: [f32; 3],
    /// Maps of its parameters (the base colour).
    pub maps: ParamMaps,
    pub ramp: Ramp,
    pub specular: Option<Hard>,
    pub rim: Option<Hard>,
}

impl PacketShader for Toon {
    #[inline(always)]
    fn shade<R: Real>(&self, input: &ShadeInput<R>, env: &ShadeEnv) -> Rgb<R> {
        let frag = input.frag;
        let n = frag.n;
        let mut params = ToonParams {
            base_color: Rgb::from_f32(self.base_color),
        };
        self.maps.fill(input, &mut params);
        let base = params.base_color;
        let diffuse = base * R::FRAC_1_PI;
        let mut acc = Rgb::zero();
        for_each_light_shadowed(input, env, |wi, e| {
            let cos = n.dot(wi);
            acc += diffuse.mul_elem(e).mul_elem(self.ramp.eval(cos));
            if let Some(s) = &self.specular {
                let h = (wi + frag.wo).normalize_or(n);
                let on = n.dot(h).ge(R::splat(s.threshold as f64)) & cos.gt(R::ZERO);
                let spec = e.mul_elem(Rgb::from_f32(s.color)) * R::FRAC_1_PI;
                acc += Rgb::select(on, spec, Rgb::zero());
            }
        });
        if let Some(l) = env.environment {
            acc += base.mul_elem(Rgb::from_f32(l));
        }
        if let Some(map) = env.env_map {
            acc += base.mul_elem(env.map_irradiance_over_pi(map, input, n));
        }
        if let Some(r) = &self.rim {
            let edge = (R::ONE - n.dot(frag.wo)).ge(R::splat(r.threshold as f64));
            acc += Rgb::select(edge, Rgb::from_f32(r.color), Rgb::zero());
        }
        acc
    }

    fn needs_surface(&self) -> bool {
        !self.maps.is_empty()
    }

    fn with_texture_filter(&self, filter: specula_raster::texture::Filter) -> Option<Toon> {
        if self.maps.is_empty() {
            return None;
        }
        let mut toon = self.clone();
        toon.maps.force_filter(filter);
        Some(toon)
    }
}
