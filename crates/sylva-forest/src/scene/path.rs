//! The camera along a scene's path: keyframes interpolated, the default fly-in and the
//! default viewpoint.

use super::*;

/// The path every scene flies in along: its `camera_path`, or [`default_camera_path`].
pub const FLY_IN: &str = "fly-in";
/// A walk at eye height through the forest ([`walk_path`]).
pub const WALK: &str = "walk";
/// A low flight across the canopy ([`low_flight_path`]).
pub const LOW_FLIGHT: &str = "low-flight";
/// The paths every scene has, by name.
pub const BUILTIN_PATHS: [&str; 3] = [FLY_IN, WALK, LOW_FLIGHT];

/// A walker's eye over the terrain, m.
pub const EYE_HEIGHT: f32 = 1.7;
/// Walking pace, m/s (a leisurely adult walk).
pub const WALK_SPEED: f32 = 1.4;
/// How long the walk lasts, s.
pub const WALK_SECONDS: f32 = 60.0;
/// Speed of the low flight, m/s.
pub const FLIGHT_SPEED: f32 = 15.0;
/// Height of the low flight over the tallest tree, m (30 … 60 m over the canopy).
pub const FLIGHT_OVER_CANOPY: f32 = 40.0;
/// How far ahead of the low flight the canopy it looks at lies, m.
pub const FLIGHT_LOOK_AHEAD: f32 = 150.0;

/// A walk at eye height ([`EYE_HEIGHT`] over the terrain) through the forest: from its
/// centre at walking pace for [`WALK_SECONDS`], along a route that turns by up to about 60°
/// to either side, looking where it goes (15 m ahead, at eye height). Keys every second.
pub fn walk_path(terrain: &Terrain) -> Vec<CameraKey> {
    let eye_at = |x: f32, y: f32| [x, y, terrain.height(x, y) + EYE_HEIGHT];
    let heading = |t: f32| 0.35 + 1.05 * (TAU * t / 40.0).sin();
    let mut keys = Vec::new();
    let (mut x, mut y) = (0.0f32, 0.0f32);
    let steps = WALK_SECONDS as usize;
    for k in 0..=steps {
        let t = k as f32;
        if k > 0 {
            // The heading over the last second, at its middle.
            let (s, c) = heading(t - 0.5).sin_cos();
            x += WALK_SPEED * c;
            y += WALK_SPEED * s;
        }
        let (s, c) = heading(t).sin_cos();
        let (tx, ty) = (x + 15.0 * c, y + 15.0 * s);
        keys.push(CameraKey { t, eye: eye_at(x, y), target: eye_at(tx, ty) });
    }
    keys
}

/// A low flight across the forest: [`FLIGHT_OVER_CANOPY`] over its tallest tree (`canopy`,
/// m above the ground) at [`FLIGHT_SPEED`], from one edge (`radius` from the centre)
/// straight over the middle until the canopy it looks at, [`FLIGHT_LOOK_AHEAD`] in front
/// and below, is the far edge (so its last view still shows the forest). Keys every two
/// seconds; the height follows the terrain.
pub fn low_flight_path(terrain: &Terrain, radius: f32, canopy: f32) -> Vec<CameraKey> {
    let length = (2.0 * radius - FLIGHT_LOOK_AHEAD).max(2.0 * FLIGHT_SPEED);
    let duration = length / FLIGHT_SPEED;
    let keys = (duration / 2.0).ceil().max(1.0) as usize;
    (0..=keys)
        .map(|k| {
            let t = duration * k as f32 / keys as f32;
            let x = -radius + FLIGHT_SPEED * t;
            let y = 0.1 * radius;
            let ahead = x + FLIGHT_LOOK_AHEAD;
            CameraKey {
                t,
                eye: [x, y, terrain.height(x, y) + canopy + FLIGHT_OVER_CANOPY],
                target: [ahead, y, terrain.height(ahead, y) + canopy],
            }
        })
        .collect()
}

/// Where the camera is at time `t` on `path` (Catmull–Rom through the keys' eyes and
/// targets, uniform in time; held at the ends), with the lens of `base`.
pub fn camera_on_path(path: &[CameraKey], t: f32, base: &Camera) -> Camera {
    let Some(first) = path.first() else { return *base };
    let last = path[path.len() - 1];
    if path.len() == 1 || t <= first.t || t >= last.t {
        let k = if t >= last.t { last } else { *first };
        return Camera { eye: k.eye, target: k.target, ..*base };
    }
    let i = path.windows(2).position(|w| t < w[1].t).unwrap_or(path.len() - 2);
    let (k1, k2) = (path[i], path[i + 1]);
    let k0 = if i > 0 { path[i - 1] } else { k1 };
    let k3 = path.get(i + 2).copied().unwrap_or(k2);
    let u = (t - k1.t) / (k2.t - k1.t);
    let spline = |a: [f32; 3], b: [f32; 3], c: [f32; 3], d: [f32; 3]| -> [f32; 3] {
        std::array::from_fn(|j| {
            let (p0, p1, p2, p3) = (a[j], b[j], c[j], d[j]);
            0.5 * (2.0 * p1
                + (p2 - p0) * u
                + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * u * u
                + (3.0 * p1 - p0 - 3.0 * p2 + p3) * u * u * u)
        })
    };
    Camera {
        eye: spline(k0.eye, k1.eye, k2.eye, k3.eye),
        target: spline(k0.target, k1.target, k2.target, k3.target),
        ..*base
    }
}

/// The path a scene without one is benchmarked along: 12 s flying in from the default
/// viewpoint towards the forest centre, descending, so trees cross LOD levels on the way.
pub fn default_camera_path(spec: &SceneSpec, radius: f32) -> Vec<CameraKey> {
    let c = default_camera(spec, radius);
    let at = |f: f32, t: f32| CameraKey {
        t,
        eye: std::array::from_fn(|i| {
            let e = c.target[i] + (c.eye[i] - c.target[i]) * f;
            if i == 2 { e.max(c.target[2] + 8.0) } else { e }
        }),
        target: c.target,
    };
    vec![at(1.0, 0.0), at(0.8, 4.0), at(0.62, 8.0), at(0.5, 12.0)]
}

/// The default viewpoint of a scene whose trees lie within `radius` of the origin.
pub fn default_camera(spec: &SceneSpec, radius: f32) -> Camera {
    let c = spec.camera.unwrap_or(CameraSpec {
        eye: [-0.9 * radius - 10.0, -1.1 * radius - 12.0, 0.35 * radius + 10.0],
        target: [0.0, 0.0, 6.0],
        fov_deg: 55.0,
    });
    Camera {
        eye: c.eye,
        target: c.target,
        fov_deg: c.fov_deg,
        near: 0.5,
        // Far enough for the ground to reach the horizon (fogged into the sky by then).
        far: (20.0 * radius + 400.0).max(8000.0),
    }
}
