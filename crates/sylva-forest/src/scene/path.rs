//! The camera along a scene's path: keyframes interpolated, the default fly-in and the
//! default viewpoint.

use super::*;

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
