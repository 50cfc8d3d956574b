//! A perspective camera: world z up, right-handed; clip depth 0 … 1 (wgpu's convention).
//! Matrices are column-major `[[f32; 4]; 4]` (`m[column][row]`), as WGSL reads them.

use sylva_core::v3::{cross, dot, norm, sub};

pub use sylva_core::mat4::{Mat4, mul};

/// Where the viewer stands and looks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position, world m.
    pub eye: [f32; 3],
    /// Point looked at, world m.
    pub target: [f32; 3],
    /// Vertical field of view, degrees.
    pub fov_deg: f32,
    /// Near and far clip distances, m.
    pub near: f32,
    /// Far clip distance, m.
    pub far: f32,
}

impl Camera {
    /// Unit viewing direction.
    pub fn forward(&self) -> [f32; 3] {
        norm(sub(self.target, self.eye))
    }

    /// World → view matrix (view space: x right, y up, looking down −z).
    pub fn view(&self) -> Mat4 {
        let f = self.forward();
        let up = if f[2].abs() > 0.999 { [0.0, 1.0, 0.0] } else { [0.0, 0.0, 1.0] };
        let s = norm(cross(f, up));
        let u = cross(s, f);
        let e = self.eye;
        [
            [s[0], u[0], -f[0], 0.0],
            [s[1], u[1], -f[1], 0.0],
            [s[2], u[2], -f[2], 0.0],
            [-dot(s, e), -dot(u, e), dot(f, e), 1.0],
        ]
    }

    /// View → clip matrix for `aspect` = width / height.
    pub fn projection(&self, aspect: f32) -> Mat4 {
        let t = 1.0 / (0.5 * self.fov_deg.to_radians()).tan();
        let (n, f) = (self.near, self.far);
        [
            [t / aspect, 0.0, 0.0, 0.0],
            [0.0, t, 0.0, 0.0],
            [0.0, 0.0, f / (n - f), -1.0],
            [0.0, 0.0, n * f / (n - f), 0.0],
        ]
    }

    /// World → clip.
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        mul(&self.projection(aspect), &self.view())
    }

    /// Fraction of the image height that an object of `size` m at `p` covers (0 behind the
    /// eye).
    pub fn screen_fraction(&self, p: [f32; 3], size: f32) -> f32 {
        self.cone(1.0).screen_fraction(p, size)
    }

    /// Whether a sphere of `radius` at `c` may be in view (conservative cone test).
    pub fn may_see(&self, c: [f32; 3], radius: f32, aspect: f32) -> bool {
        self.cone(aspect).may_see(c, radius)
    }

    /// How far along the view the sun's shadow map reaches, m: its near cascade 1.2 × the
    /// distance to the point looked at, within 40 … 250 m, and its far cascade four times
    /// that, at most 1200 m. The renderer draws its cascades for these; beyond the far one
    /// nothing takes a shadow.
    pub fn shadow_reach(&self) -> (f32, f32) {
        let near = (1.2 * dot(sub(self.target, self.eye), sub(self.target, self.eye)).sqrt())
            .clamp(40.0, 250.0);
        (near, (4.0 * near).min(ShadowSweep::MAX_LENGTH))
    }

    /// The sphere a shadow cascade covers for the first `reach` m of the view in an image
    /// of `aspect` = width / height: centred halfway along them, its radius out to the
    /// view's corners at `reach`. Returns (centre, radius).
    pub fn shadow_sphere(&self, aspect: f32, reach: f32) -> ([f32; 3], f32) {
        let f = self.forward();
        let tan_v = (0.5 * self.fov_deg.to_radians()).tan();
        let radius = reach * (0.25 + tan_v * tan_v * (1.0 + aspect * aspect)).sqrt();
        let e = self.eye;
        ([e[0] + f[0] * 0.5 * reach, e[1] + f[1] * 0.5 * reach, e[2] + f[2] * 0.5 * reach], radius)
    }

    /// The view cone for an image of `aspect` = width / height, with what per-object tests
    /// need precomputed.
    pub fn cone(&self, aspect: f32) -> ViewCone {
        let half_v = 0.5 * self.fov_deg.to_radians();
        let half_diag = (half_v.tan() * (1.0 + aspect * aspect).sqrt()).atan();
        let (sin_h, cos_h) = half_diag.sin_cos();
        ViewCone {
            eye: self.eye,
            forward: self.forward(),
            cos_h,
            sin_h,
            inv_height: 1.0 / (2.0 * half_v.tan()),
            far: self.far,
        }
    }
}

/// Orbit camera: yaw and pitch about a target, at a distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    /// Point looked at, world m.
    pub target: [f32; 3],
    /// Azimuth of the eye about the target, rad.
    pub yaw: f32,
    /// Elevation of the eye, rad.
    pub pitch: f32,
    /// Eye to target, m.
    pub distance: f32,
    /// Vertical field of view, degrees.
    pub fov: f32,
    /// Far plane, m.
    pub far: f32,
}

impl Orbit {
    /// The orbit that sees what `c` sees.
    pub fn from_camera(c: &Camera) -> Orbit {
        let d = [c.eye[0] - c.target[0], c.eye[1] - c.target[1], c.eye[2] - c.target[2]];
        let distance = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-3);
        Orbit {
            target: c.target,
            yaw: d[1].atan2(d[0]),
            pitch: (d[2] / distance).clamp(-1.0, 1.0).asin(),
            distance,
            fov: c.fov_deg,
            far: c.far,
        }
    }

    /// The camera.
    pub fn camera(&self) -> Camera {
        let (cp, sp) = (self.pitch.cos(), self.pitch.sin());
        let eye = [
            self.target[0] + self.distance * cp * self.yaw.cos(),
            self.target[1] + self.distance * cp * self.yaw.sin(),
            self.target[2] + self.distance * sp,
        ];
        Camera { eye, target: self.target, fov_deg: self.fov, near: 0.5, far: self.far }
    }

    /// The ray (origin, unit direction) through pixel (`x`, `y`) of a `w × h` image.
    pub fn ray(&self, x: f32, y: f32, w: f32, h: f32) -> ([f32; 3], [f32; 3]) {
        let c = self.camera();
        let f = c.forward();
        let up = [0.0, 0.0, 1.0];
        let r = norm(cross(f, up));
        let u = cross(r, f);
        let t = (0.5 * c.fov_deg.to_radians()).tan();
        let (sx, sy) = ((2.0 * x / w - 1.0) * t * w / h, (1.0 - 2.0 * y / h) * t);
        let d: [f32; 3] = std::array::from_fn(|i| f[i] + sx * r[i] + sy * u[i]);
        (c.eye, norm(d))
    }

    /// Turn the eye about the target for a pointer dragged by (`dx`, `dy`) pixels: right
    /// turns the view left, down raises the eye (pitch held between −0.1 and 1.5 rad).
    pub fn drag(&mut self, dx: f32, dy: f32) {
        self.yaw -= 0.005 * dx;
        self.pitch = (self.pitch + 0.005 * dy).clamp(-0.1, 1.5);
    }

    /// Move the eye towards the target by `steps` wheel lines (10 % each; negative: away),
    /// between 2 m and 5 km.
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * 0.9f32.powf(steps)).clamp(2.0, 5000.0);
    }

    /// Move the target over `dt` seconds by `forward` (along the view, level), `right` and
    /// `up`, each −1 … 1, at a speed that grows with the distance to it.
    pub fn travel(&mut self, forward: f32, right: f32, up: f32, dt: f32) {
        let speed = 0.8 * self.distance.max(10.0) * dt;
        let (fx, fy) = (-self.yaw.cos(), -self.yaw.sin());
        let mv = [forward * fx + right * fy, forward * fy - right * fx, up];
        for (t, m) in self.target.iter_mut().zip(mv) {
            *t += m * speed;
        }
    }
}

/// A camera's view cone (the cone around the view direction through the image corners),
/// for per-object culling and projected sizes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewCone {
    eye: [f32; 3],
    forward: [f32; 3],
    cos_h: f32,
    sin_h: f32,
    /// 1 / (2 tan(fov / 2)): image heights per unit of size / depth.
    inv_height: f32,
    far: f32,
}

impl ViewCone {
    /// Whether a sphere of `radius` at `c` may be in view: the angle φ between the view
    /// direction and the centre, less the sphere's angular radius β = asin(r / d), is at most
    /// the half-angle h; as cosines (h + β ≤ π), d·f ≥ cos h √(d² − r²) − r sin h.
    pub fn may_see(&self, c: [f32; 3], radius: f32) -> bool {
        self.sees(sub(c, self.eye), radius)
    }

    /// [`may_see`](Self::may_see) for a sphere at `d` from the eye, without branches (both
    /// square roots are taken; a camera inside the sphere is a select), so that a loop over
    /// many spheres vectorises ([`may_see_trees`]).
    #[inline(always)]
    fn sees(&self, d: [f32; 3], radius: f32) -> bool {
        let dist2 = dot(d, d);
        let along = dot(d, self.forward);
        let in_cone = along >= self.cos_h * (dist2 - radius * radius).sqrt() - radius * self.sin_h;
        let near = dist2.sqrt() - radius < self.far;
        dist2 <= radius * radius || (in_cone & near)
    }

    /// Fraction of the image height that an object of `size` m at `p` covers (0 behind the
    /// eye).
    pub fn screen_fraction(&self, p: [f32; 3], size: f32) -> f32 {
        let depth = dot(sub(p, self.eye), self.forward);
        if depth <= 0.0 {
            return 0.0;
        }
        size * self.inv_height / depth
    }

    /// Fraction of the image height that an object of `size` m at `p` would cover facing the
    /// eye at its distance: [`screen_fraction`](Self::screen_fraction) by distance instead
    /// of depth (no larger, and large for an object beside or behind the eye).
    pub fn size_fraction(&self, p: [f32; 3], size: f32) -> f32 {
        let d = sub(p, self.eye);
        size * self.inv_height / dot(d, d).sqrt().max(1e-6)
    }

    /// Whether the shadow of a sphere of `radius` at `c` may fall in view: the sphere
    /// swept `length` m along the unit direction `away` (away from the sun, downwards) may
    /// meet the cone. The swept sphere (a capsule) is covered by spheres of radius
    /// √(r² + (s/2)²) at steps of s ≥ r / 2 along it (at most [`SHADOW_SAMPLES`] of them),
    /// so the answer is conservative: false only where no part of the capsule is in view.
    /// The sphere itself is not tested (the caller culls it on its own).
    pub fn may_see_shadow(&self, c: [f32; 3], radius: f32, away: [f32; 3], length: f32) -> bool {
        if length.is_nan() || length <= 0.0 {
            return false;
        }
        let step = (0.5 * radius).max(length / SHADOW_SAMPLES as f32);
        let grown = (radius * radius + 0.25 * step * step).sqrt();
        let n = (length / step).ceil() as usize;
        (1..=n.min(SHADOW_SAMPLES)).any(|k| {
            let t = (k as f32 * step).min(length);
            self.may_see([c[0] + t * away[0], c[1] + t * away[1], c[2] + t * away[2]], grown)
        })
    }

    /// Whether the sphere of `radius` at `c` lies wholly inside the cone and nearer than its
    /// far end, the eye outside it: then [`may_see`](Self::may_see) keeps every sphere
    /// inside it. Returns the sphere's nearest distance and nearest depth from the eye.
    pub fn holds(&self, c: [f32; 3], radius: f32) -> Option<(f32, f32)> {
        let d = sub(c, self.eye);
        let dist = dot(d, d).sqrt();
        if !(dist > radius && dist + radius < self.far && self.cos_h > 0.0) {
            return None;
        }
        // The angle φ from the axis to the centre plus the sphere's angular radius β at most
        // the half-angle h: cos(φ + β) ≥ cos h (φ + β < 3π/2 and h < π/2).
        let cos_phi = (dot(d, self.forward) / dist).clamp(-1.0, 1.0);
        let sin_phi = (1.0 - cos_phi * cos_phi).max(0.0).sqrt();
        let sin_b = radius / dist;
        let cos_b = (1.0 - sin_b * sin_b).max(0.0).sqrt();
        if cos_phi * cos_b - sin_phi * sin_b < self.cos_h {
            return None;
        }
        Some((dist - radius, dot(d, self.forward) - radius))
    }

    /// Fraction of the image height an object of `size` m covers at `depth` m.
    pub fn fraction_at(&self, size: f32, depth: f32) -> f32 {
        size * self.inv_height / depth
    }

    /// Whether an object of `size` m at `p`, in front of the eye, covers less than `bound` of
    /// the image height: [`screen_fraction`](Self::screen_fraction) without its division.
    /// Behind the eye it answers false, as it may where the fraction is within rounding of
    /// `bound`: a caller leaves a margin.
    pub fn fraction_below(&self, p: [f32; 3], size: f32, bound: f32) -> bool {
        size * self.inv_height < bound * dot(sub(p, self.eye), self.forward)
    }
}

/// What one cascade of the sun's shadow map holds: an orthographic view along the sun's
/// rays of the sphere around the first `reach` m of the view ([`Camera::shadow_sphere`]),
/// its image a square `2 radius` wide, its depth reaching [`ShadowBox::BEYOND`] m past the
/// sphere on either side (so tall trees outside it still cast into it). The renderer draws
/// the cascade from it; lit pixels anywhere in the square take its shadows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowBox {
    /// Centre of the sphere, world m.
    pub centre: [f32; 3],
    /// Radius of the sphere: half the square's side, m.
    pub radius: f32,
    /// Unit axes: right and up across the sun's view, and along its rays (away from the sun).
    pub right: [f32; 3],
    /// See [`ShadowBox::right`].
    pub up: [f32; 3],
    /// See [`ShadowBox::right`].
    pub along: [f32; 3],
}

impl ShadowBox {
    /// Depth the cascade reaches past its sphere, m.
    pub const BEYOND: f32 = 150.0;

    /// Texels along each side of a cascade.
    pub const TEXELS: u32 = 1024;

    /// The cascade of `camera` for the first `reach` m of the view (image `aspect` = width
    /// / height) and a sun in direction `sun` (towards it).
    pub fn new(camera: &Camera, aspect: f32, reach: f32, sun: [f32; 3]) -> ShadowBox {
        let (centre, radius) = camera.shadow_sphere(aspect, reach);
        let along = norm([-sun[0], -sun[1], -sun[2]]);
        let right = if along[0].abs() + along[1].abs() < 1e-4 {
            [1.0, 0.0, 0.0]
        } else {
            norm(cross(along, [0.0, 0.0, 1.0]))
        };
        let up = cross(right, along);
        ShadowBox { centre, radius, right, up, along }
    }

    /// Whether a sphere of `radius` at `c`, swept `length` m away from the sun, may cast
    /// into the cascade: across the sun's view the sphere overlaps the square (the sweep
    /// runs along the rays, so it does not move there), and along them the sweep overlaps
    /// the depth the cascade holds. `margin` m widens the square (the renderer snaps its
    /// centre to whole texels).
    pub fn may_take(&self, c: [f32; 3], radius: f32, length: f32, margin: f32) -> bool {
        let d = sub(c, self.centre);
        let side = self.radius + radius + margin;
        let deep = self.radius + ShadowBox::BEYOND + radius;
        let a = dot(d, self.along);
        dot(d, self.right).abs() <= side
            && dot(d, self.up).abs() <= side
            && a + length.max(0.0) >= -deep
            && a <= deep
    }
}

/// Most spheres [`ViewCone::may_see_shadow`] tests along one swept sphere.
pub const SHADOW_SAMPLES: usize = 64;

/// How trees' shadows are swept for culling: away from the sun, until below the ground.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowSweep {
    /// Unit direction away from the sun (the way shadows fall; z < 0).
    pub away: [f32; 3],
    /// Length of the sweep per metre of tree height.
    pub per_height: f32,
}

impl ShadowSweep {
    /// Longest sweep, m: as far as the shadow map reaches along the view (its far
    /// cascade's farthest reach).
    pub const MAX_LENGTH: f32 = 1200.0;

    /// The sweep for a sun in unit direction `sun` (towards it; world z up): a tree `h` m
    /// tall has its crown sphere (radius 0.75 h about the point h / 2 up) swept until the
    /// sphere's top has sunk a quarter of the tree's height below its foot (ground that
    /// falls away from a tree still takes its shadow), that is 1.5 h / sin(elevation), at
    /// most [`ShadowSweep::MAX_LENGTH`]. `None` for a sun at or below the horizon (no
    /// shadows are cast) or a direction that is not finite.
    pub fn new(sun: [f32; 3]) -> Option<ShadowSweep> {
        let n = dot(sun, sun).sqrt();
        if !(n.is_finite() && n > 0.0) || sun[2] / n <= 1e-3 {
            return None;
        }
        let s = [sun[0] / n, sun[1] / n, sun[2] / n];
        Some(ShadowSweep { away: [-s[0], -s[1], -s[2]], per_height: 1.5 / s[2] })
    }

    /// Length of the sweep of a tree `h` m tall, m.
    #[inline(always)]
    pub fn length(&self, h: f32) -> f32 {
        (self.per_height * h).min(ShadowSweep::MAX_LENGTH)
    }
}

sylva_core::simd_kernel! {
    /// For a run of trees that the cone does not see (`seen[i]` false), whether their crown
    /// swept by `sweep` may reach the view, tested as the one sphere that holds the whole
    /// sweep (centre halfway along it, radius half its length plus the crown's): a coarse,
    /// conservative first cut, many trees at a time, before [`ViewCone::may_see_shadow`]
    /// tests the few it keeps. Trees as [`may_see_trees`] takes them; `shade[i]` is false
    /// where `seen[i]` is true.
    pub fn may_shade_trees(
        cone: &ViewCone,
        sweep: &ShadowSweep,
        x: &[f32],
        y: &[f32],
        z: &[f32],
        h: &[f32],
        seen: &[bool],
        shade: &mut [bool],
    ) {
        let n = shade.len();
        let (x, y, z, h, seen) = (&x[..n], &y[..n], &z[..n], &h[..n], &seen[..n]);
        let a = sweep.away;
        for i in 0..n {
            let half = 0.5 * sweep.length(h[i]);
            let c = [x[i] + half * a[0], y[i] + half * a[1], z[i] + 0.5 * h[i] + half * a[2]];
            shade[i] = !seen[i] & cone.sees(sub(c, cone.eye), half + 0.75 * h[i]);
        }
    }
}

sylva_core::simd_kernel! {
    /// [`ViewCone::may_see`] for a run of trees, one flag each into `seen`: tree `i` stands
    /// at (`x[i]`, `y[i]`, `z[i]`) and is `h[i]` m tall, its crown the sphere of radius
    /// 0.75 h about the point h / 2 up, as [`Forest::frame`](crate::Forest::frame) culls
    /// it. The same test, lane by lane, so the same flags, computed many trees at a time.
    pub fn may_see_trees(
        cone: &ViewCone,
        x: &[f32],
        y: &[f32],
        z: &[f32],
        h: &[f32],
        seen: &mut [bool],
    ) {
        let n = seen.len();
        let (x, y, z, h) = (&x[..n], &y[..n], &z[..n], &h[..n]);
        for i in 0..n {
            let c = [x[i], y[i], z[i] + 0.5 * h[i]];
            seen[i] = cone.sees(sub(c, cone.eye), 0.75 * h[i]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(m: &Mat4, p: [f32; 3]) -> [f32; 4] {
        let mut o = [0.0; 4];
        for r in 0..4 {
            o[r] = m[0][r] * p[0] + m[1][r] * p[1] + m[2][r] * p[2] + m[3][r];
        }
        o
    }

    #[test]
    fn target_lands_mid_screen_and_depth_runs_zero_to_one() {
        let c = Camera {
            eye: [0.0, -10.0, 2.0],
            target: [0.0, 0.0, 2.0],
            fov_deg: 60.0,
            near: 0.5,
            far: 100.0,
        };
        let vp = c.view_projection(1.5);
        let t = apply(&vp, c.target);
        assert!((t[0] / t[3]).abs() < 1e-5 && (t[1] / t[3]).abs() < 1e-5);
        let near = apply(&vp, [0.0, -9.5, 2.0]);
        let far = apply(&vp, [0.0, 90.0, 2.0]);
        assert!((near[2] / near[3]).abs() < 1e-4 && (far[2] / far[3] - 1.0).abs() < 1e-4);
        // World up is screen up; world +x is screen right (looking along +y).
        let up = apply(&vp, [0.0, 0.0, 3.0]);
        let right = apply(&vp, [1.0, 0.0, 2.0]);
        assert!(up[1] / up[3] > 0.0 && right[0] / right[3] > 0.0);
        assert!(c.may_see([0.0, 0.0, 2.0], 1.0, 1.5) && !c.may_see([0.0, -20.0, 2.0], 1.0, 1.5));
    }

    #[test]
    fn the_cone_test_agrees_with_the_angles() {
        // Against the angle form: φ − asin(r/d) ≤ h, sampled around the cone's edge.
        let c = Camera {
            eye: [1.0, -3.0, 2.0],
            target: [4.0, 8.0, 1.0],
            fov_deg: 55.0,
            near: 0.5,
            far: 1e4,
        };
        let aspect = 4.0 / 3.0;
        let cone = c.cone(aspect);
        let f = c.forward();
        let h = ((0.5 * c.fov_deg.to_radians()).tan() * (1.0f32 + aspect * aspect).sqrt()).atan();
        let (mut inside, mut outside) = (0, 0);
        for k in 0..2000 {
            let a = k as f32 * 0.37;
            let p =
                [1.0 + 30.0 * (a * 1.3).cos(), -3.0 + 30.0 * a.sin(), 2.0 + 9.0 * (a * 0.7).sin()];
            let r = 0.5 + (k % 7) as f32;
            let d = sub(p, c.eye);
            let dist = dot(d, d).sqrt();
            let phi = (dot(d, f) / dist).clamp(-1.0, 1.0).acos();
            let margin = phi - (r / dist).min(1.0).asin() - h;
            if margin.abs() < 1e-3 {
                continue;
            }
            assert_eq!(cone.may_see(p, r), margin < 0.0, "point {p:?}, radius {r}");
            if margin < 0.0 { inside += 1 } else { outside += 1 }
        }
        assert!(inside > 100 && outside > 100);
    }

    #[test]
    fn fraction_below_is_the_projected_size_below_a_bound() {
        // Against the fraction itself, away from the bound by more than rounding; behind
        // the eye (fraction 0) it declines to answer.
        let c = Camera {
            eye: [2.0, 1.0, 3.0],
            target: [9.0, 40.0, 0.0],
            fov_deg: 50.0,
            near: 0.5,
            far: 1e4,
        };
        let cone = c.cone(1.5);
        let (mut below, mut above) = (0, 0);
        for k in 0..3000 {
            let a = k as f32 * 0.53;
            let p = [2.0 + 60.0 * a.cos(), 1.0 + 60.0 * (1.1 * a).sin(), 3.0 + 5.0 * a.sin()];
            let size = 1.0 + (k % 13) as f32;
            let bound = 0.01 * (1 + k % 29) as f32;
            let frac = cone.screen_fraction(p, size);
            if frac == 0.0 {
                assert!(!cone.fraction_below(p, size, bound), "behind the eye: {p:?}");
            } else if (frac / bound - 1.0).abs() > 1e-5 {
                assert_eq!(cone.fraction_below(p, size, bound), frac < bound, "{p:?}, {size}");
                if frac < bound { below += 1 } else { above += 1 }
            }
        }
        assert!(below > 300 && above > 300, "{below} below, {above} above");
    }

    #[test]
    fn trees_culled_many_at_a_time_are_culled_as_one_at_a_time() {
        // Trees scattered round the eye (some with the eye inside the crown, some past the
        // far distance), and trees placed where `may_see` flips, found to the last bit
        // along lines that cross the cone's side or the far distance: the run's flags are
        // `may_see`'s, tree by tree.
        let c = Camera {
            eye: [-40.0, 7.0, 30.0],
            target: [0.0, 0.0, 0.0],
            fov_deg: 45.0,
            near: 1.0,
            far: 90.0,
        };
        let cone = c.cone(16.0 / 9.0);
        let f = c.forward();
        let (mut x, mut y, mut z, mut h) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut add = |p: [f32; 3], height: f32| {
            x.push(p[0]);
            y.push(p[1]);
            z.push(p[2]);
            h.push(height);
        };
        for k in 0..3000 {
            let a = k as f32 * 0.37;
            let reach = 1.0 + (k % 40) as f32 * 3.0;
            let p =
                [-40.0 + reach * a.cos(), 7.0 + reach * (1.3 * a).sin(), 30.0 - reach * a.sin()];
            add(p, 2.0 + (k % 9) as f32 * 3.0);
        }
        let seen_one = |p: [f32; 3], height: f32| {
            cone.may_see([p[0], p[1], p[2] + 0.5 * height], 0.75 * height)
        };
        for k in 0..300 {
            let height = 4.0 + (k % 7) as f32 * 5.0;
            let s = k as f32 * 0.61;
            let a = [0, 1, 2].map(|i| c.eye[i] + 20.0 * f[i]);
            let b = if k % 3 == 2 {
                [0, 1, 2].map(|i| c.eye[i] + (c.far + 80.0) * f[i])
            } else {
                [0, 1, 2].map(|i| a[i] + 80.0 * [s.cos(), s.sin(), (1.7 * s).sin()][i])
            };
            let at = |t: f32| [0, 1, 2].map(|i| a[i] + t * (b[i] - a[i]));
            if !seen_one(at(0.0), height) || seen_one(at(1.0), height) {
                continue;
            }
            let (mut lo, mut hi) = (0.0f32, 1.0f32);
            while lo.next_up() < hi {
                let mid = (0.5 * (lo + hi)).clamp(lo.next_up(), hi.next_down());
                if seen_one(at(mid), height) { lo = mid } else { hi = mid }
            }
            let mut t = lo;
            for _ in 0..4 {
                t = t.next_down();
            }
            for _ in 0..9 {
                add(at(t), height);
                t = t.next_up();
            }
        }
        let mut seen = vec![false; x.len()];
        may_see_trees(&cone, &x, &y, &z, &h, &mut seen);
        let (mut yes, mut no) = (0, 0);
        for i in 0..x.len() {
            let want = seen_one([x[i], y[i], z[i]], h[i]);
            assert_eq!(seen[i], want, "tree {i} at {:?}, {} m", [x[i], y[i], z[i]], h[i]);
            if want { yes += 1 } else { no += 1 }
        }
        assert!(yes > 1000 && no > 1000 && x.len() > 4000, "{yes} seen, {no} not, of {}", x.len());
    }

    #[test]
    fn a_crown_casts_into_a_cascade_wherever_part_of_its_sweep_lies_in_its_box() {
        // A camera over flat ground, the far cascade for a low and a high sun; crowns on a
        // spiral out to 1.5 km. Wherever a sphere of the crown's radius at some point of the
        // sweep (stepped by 1/200 of its length) meets the cascade's box — the square across
        // the sun's view, the depth along its rays — the crown is kept; some are not.
        let c = Camera {
            eye: [0.0, 0.0, 30.0],
            target: [20.0, 30.0, 0.0],
            fov_deg: 50.0,
            near: 0.5,
            far: 2000.0,
        };
        for elevation in [15.0f32, 60.0] {
            let (ce, se) = (elevation.to_radians().cos(), elevation.to_radians().sin());
            let sun = [-0.6 * ce, -0.8 * ce, se];
            let b = ShadowBox::new(&c, 1.5, c.shadow_reach().1, sun);
            let sweep = ShadowSweep::new(sun).expect("sun up");
            let inside = |q: [f32; 3], r: f32| {
                let d = sub(q, b.centre);
                // Distance from the sphere's centre to the box, axis by axis.
                let out = |v: f32, half: f32| (v.abs() - half).max(0.0);
                let (a, s) = (dot(d, b.along), b.radius);
                let o = [out(dot(d, b.right), s), out(dot(d, b.up), s), out(a, s + 150.0)];
                dot(o, o) <= r * r
            };
            let (mut kept, mut dropped) = (0, 0);
            for k in 0..3000 {
                let a = k as f32 * 0.37;
                let reach = 10.0 * (k % 150) as f32;
                let h = 8.0 + (k % 5) as f32 * 6.0;
                let crown = [reach * a.cos(), reach * a.sin(), 0.5 * h];
                let (r, len) = (0.75 * h, sweep.length(h));
                let meets = (0..=200).any(|i| {
                    let t = len * i as f32 / 200.0;
                    inside([0, 1, 2].map(|j| crown[j] + t * sweep.away[j]), r)
                });
                let take = b.may_take(crown, r, len, 0.0);
                assert!(take || !meets, "crown at {crown:?} meets the box but is dropped");
                if take { kept += 1 } else { dropped += 1 }
            }
            assert!(kept > 100 && dropped > 100, "{elevation}°: {kept} kept, {dropped} dropped");
        }
        // A crown in a corner of the square, outside the circle in it, is kept (the map
        // holds the square; lit pixels there take its shadows).
        let b = ShadowBox::new(&c, 1.5, 160.0, [0.0, 0.0, 1.0]);
        let corner = [0, 1, 2].map(|j| b.centre[j] + 0.9 * b.radius * (b.right[j] + b.up[j]));
        assert!(b.may_take(corner, 1.0, 10.0, 0.0));
        let beyond = [0, 1, 2].map(|j| b.centre[j] + 1.1 * b.radius * b.right[j]);
        assert!(!b.may_take(beyond, 1.0, 10.0, 0.0));
    }

    #[test]
    fn a_swept_crown_is_kept_wherever_part_of_its_sweep_is_in_view() {
        // Trees scattered round a camera looking down, sweeps for a low and a high sun:
        // wherever a sphere of the crown's radius at some point along the sweep (found by
        // stepping 1/400 of its length) is in view, both the first cut and the fine test
        // keep the tree; and the fine test keeps no tree the first cut drops.
        let c = Camera {
            eye: [0.0, 0.0, 40.0],
            target: [30.0, 40.0, 0.0],
            fov_deg: 50.0,
            near: 0.5,
            far: 1500.0,
        };
        let cone = c.cone(4.0 / 3.0);
        for elevation in [12.0f32, 20.0, 49.0, 75.0] {
            let (ce, se) = (elevation.to_radians().cos(), elevation.to_radians().sin());
            let sweep = ShadowSweep::new([-0.6 * ce, -0.8 * ce, se]).expect("sun up");
            let (mut x, mut y, mut z, mut h) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for k in 0..2000 {
                let a = k as f32 * 0.41;
                let reach = 5.0 + (k % 50) as f32 * 4.0;
                x.push(reach * a.cos());
                y.push(reach * (1.3 * a).sin());
                z.push(0.0);
                h.push(8.0 + (k % 7) as f32 * 4.0);
            }
            let mut seen = vec![false; x.len()];
            may_see_trees(&cone, &x, &y, &z, &h, &mut seen);
            let mut shade = vec![true; x.len()];
            may_shade_trees(&cone, &sweep, &x, &y, &z, &h, &seen, &mut shade);
            let (mut kept, mut dropped) = (0, 0);
            for i in 0..x.len() {
                if seen[i] {
                    assert!(!shade[i], "a tree in view is not a shadow-only one");
                    continue;
                }
                let (r, len, a) = (0.75 * h[i], sweep.length(h[i]), sweep.away);
                let c0 = [x[i], y[i], z[i] + 0.5 * h[i]];
                let fine = cone.may_see_shadow(c0, r, a, len);
                let truth = (1..=400).any(|k| {
                    let t = len * k as f32 / 400.0;
                    cone.may_see([c0[0] + t * a[0], c0[1] + t * a[1], c0[2] + t * a[2]], r)
                });
                if truth {
                    assert!(fine && shade[i], "{elevation}°, tree {i}: sweep in view, dropped");
                }
                assert!(shade[i] || !fine, "{elevation}°, tree {i}: kept by the fine test only");
                if fine { kept += 1 } else { dropped += 1 }
            }
            assert!(kept > 20 && dropped > 200, "{elevation}°: {kept} kept, {dropped} dropped");
        }
        // A sun on or below the horizon casts no shadows to sweep.
        assert!(ShadowSweep::new([1.0, 0.0, 0.0]).is_none());
        assert!(ShadowSweep::new([0.0, 0.3, -1.0]).is_none());
        assert!(ShadowSweep::new([f32::NAN, 0.0, 1.0]).is_none());
    }
}
