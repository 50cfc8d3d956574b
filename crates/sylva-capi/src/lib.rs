//! A C ABI onto the live simulation, for engines that are not Rust or not wgpu (a Godot,
//! Unity or Unreal plugin, a C++ renderer): the header is `include/sylva.h`, the library
//! this crate's `cdylib` (`libsylva_capi.so`, `sylva_capi.dll`, `libsylva_capi.dylib`).
//!
//! A host creates a forest from a built-in scene or a scene file, steps it by its own clock,
//! builds a frame for its camera, and reads the frame's arrays in place: the instances
//! (`SylvaInstance`: trunk base, yaw, scale, where its joint palettes lie, leaf flutter,
//! cross-fade range, level tag), the buckets (one instanced draw per species and level) and
//! the joint palettes (3×4 row-major matrices, rest pose → animated, tree space), indexed by
//! the forest's joints in its LOD order. The meshes those palettes skin are handed out per
//! species and level (`sylva_species_mesh`: branch vertices and triangles, leaf cards),
//! with the bark texture and the leaf atlas (`sylva_species_texture`), so a host can draw
//! the trees itself. The frame arrays stay valid until the next `sylva_forest_frame` or
//! `sylva_forest_free`; the meshes and textures until `sylva_forest_free`.
//!
//! Conventions: Z-up, metres, seconds, m/s. Errors: a function that fails returns NULL or
//! a non-zero status and leaves a message for `sylva_last_error` on the calling thread.
//! The interface is versioned by `SYLVA_ABI_VERSION` (`sylva_abi_version`): a layout or
//! signature change raises it.

use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char};

use sylva_forest::{Bucket, Camera, Forest, FrameData, Instance, SceneSpec};
use sylva_tree::mesh::LeafCluster;

/// The version of this interface: raised by any change to a signature or a struct's layout.
pub const SYLVA_ABI_VERSION: u32 = 2;

/// A forest and its last frame, behind an opaque pointer.
#[derive(Debug)]
pub struct SylvaForest {
    forest: Forest,
    frame: FrameData,
    buckets: Vec<SylvaBucket>,
}

/// A camera: eye and target (world m), vertical field of view (degrees), clip distances (m).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SylvaCamera {
    /// Eye position, world m.
    pub eye: [f32; 3],
    /// Point looked at, world m.
    pub target: [f32; 3],
    /// Vertical field of view, degrees.
    pub fov_deg: f32,
    /// Near clip distance, m.
    pub near: f32,
    /// Far clip distance, m.
    pub far: f32,
}

/// One instanced draw: `count` instances from `first`, of one species at one level
/// (`level` equal to the species' number of mesh levels: its impostor); `shadow_only`
/// draws go to the shadow map alone, cast at mesh level `shadow_level`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SylvaBucket {
    /// Species index, in the scene's order.
    pub species: u32,
    /// Level drawn.
    pub level: u32,
    /// The mesh level the shadows are cast with.
    pub shadow_level: u32,
    /// First instance.
    pub first: u32,
    /// Instances.
    pub count: u32,
    /// 1: drawn into the shadow map only.
    pub shadow_only: u32,
}

thread_local! {
    static LAST_ERROR: RefCell<Option<CString>> = const { RefCell::new(None) };
}

fn fail(message: String) {
    let text = CString::new(message.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = Some(text));
}

/// This interface's version, [`SYLVA_ABI_VERSION`].
#[unsafe(no_mangle)]
pub extern "C" fn sylva_abi_version() -> u32 {
    SYLVA_ABI_VERSION
}

/// The size of `SylvaInstance` in bytes, for a host to check its declaration against.
#[unsafe(no_mangle)]
pub extern "C" fn sylva_instance_size() -> usize {
    std::mem::size_of::<Instance>()
}

/// The last error on this thread, or NULL; valid until the next failing call on it.
#[unsafe(no_mangle)]
pub extern "C" fn sylva_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ref().map_or(std::ptr::null(), |s| s.as_ptr()))
}

/// A forest from `scene`: a built-in name (`small`, `A` … `D`) or a scene file's path
/// (UTF-8). NULL on error (see `sylva_last_error`).
///
/// # Safety
/// `scene` is NULL or a NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_forest_new(scene: *const c_char) -> *mut SylvaForest {
    if scene.is_null() {
        fail("sylva_forest_new: scene is NULL".into());
        return std::ptr::null_mut();
    }
    // SAFETY: the caller passes a NUL-terminated string.
    let name = unsafe { CStr::from_ptr(scene) }.to_string_lossy().into_owned();
    let built = SceneSpec::load(&name)
        .map_err(|e| e.to_string())
        .and_then(|spec| Forest::new(&spec).map_err(|e| e.to_string()));
    match built {
        Ok(forest) => Box::into_raw(Box::new(SylvaForest {
            forest,
            frame: FrameData::default(),
            buckets: Vec::new(),
        })),
        Err(e) => {
            fail(format!("scene {name}: {e}"));
            std::ptr::null_mut()
        }
    }
}

/// Free a forest (NULL: nothing).
///
/// # Safety
/// `f` is NULL or a forest from `sylva_forest_new` not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_forest_free(f: *mut SylvaForest) {
    if !f.is_null() {
        // SAFETY: made by `Box::into_raw` in `sylva_forest_new`, freed once.
        drop(unsafe { Box::from_raw(f) });
    }
}

/// The handle behind `f`, or None for NULL.
///
/// # Safety
/// `f` is NULL or a live forest, not used elsewhere meanwhile.
unsafe fn forest<'a>(f: *mut SylvaForest) -> Option<&'a mut SylvaForest> {
    // SAFETY: guaranteed by the caller.
    unsafe { f.as_mut() }
}

/// Step the forest by `dt` seconds of simulated time. Returns 0, or 1 for a NULL forest.
///
/// # Safety
/// `f` is NULL or a live forest.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_forest_step(f: *mut SylvaForest, dt: f32) -> i32 {
    // SAFETY: guaranteed by the caller.
    let Some(f) = (unsafe { forest(f) }) else { return 1 };
    f.forest.step(dt);
    0
}

/// The scene's own camera (its path's start, or its fixed camera). A NULL forest gives a
/// zeroed camera.
///
/// # Safety
/// `f` is NULL or a live forest.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_forest_default_camera(f: *mut SylvaForest) -> SylvaCamera {
    // SAFETY: guaranteed by the caller.
    let Some(f) = (unsafe { forest(f) }) else {
        return SylvaCamera { eye: [0.0; 3], target: [0.0; 3], fov_deg: 0.0, near: 0.0, far: 0.0 };
    };
    let c = f.forest.default_camera();
    SylvaCamera { eye: c.eye, target: c.target, fov_deg: c.fov_deg, near: c.near, far: c.far }
}

/// Build the frame for `camera` and an image `aspect` = width / height, `rows` pixels
/// tall. Returns 0, 1 for a NULL argument, 2 for a camera that is not finite.
///
/// # Safety
/// `f` is NULL or a live forest; `camera` is NULL or points to a camera.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_forest_frame(
    f: *mut SylvaForest,
    camera: *const SylvaCamera,
    aspect: f32,
    rows: u32,
) -> i32 {
    // SAFETY: guaranteed by the caller.
    let (Some(f), Some(c)) = (unsafe { forest(f) }, unsafe { camera.as_ref() }) else {
        fail("sylva_forest_frame: forest or camera is NULL".into());
        return 1;
    };
    let rest = [c.fov_deg, c.near, c.far, aspect];
    if !c.eye.iter().chain(&c.target).chain(&rest).all(|v| v.is_finite()) || c.eye == c.target {
        fail(format!("sylva_forest_frame: camera {c:?}, aspect {aspect}: not finite"));
        return 2;
    }
    let camera =
        Camera { eye: c.eye, target: c.target, fov_deg: c.fov_deg, near: c.near, far: c.far };
    f.frame.image_rows = rows;
    f.forest.frame(&camera, aspect, &mut f.frame);
    f.buckets.clear();
    f.buckets.extend(f.frame.buckets.iter().map(|b: &Bucket| SylvaBucket {
        species: b.species,
        level: b.lod,
        shadow_level: b.shadow_lod,
        first: b.first,
        count: b.count,
        shadow_only: b.shadow_only as u32,
    }));
    0
}

/// Set `*count` to the length of a frame array and return its start (NULL and 0 for a
/// NULL forest).
fn array<T>(items: &[T], count: *mut usize) -> *const T {
    if !count.is_null() {
        // SAFETY: checked non-NULL; the caller passes a place for one `size_t`.
        unsafe { *count = items.len() };
    }
    items.as_ptr()
}

/// The last frame's joint palettes: `*count` floats (3×4 row-major matrices, laid out as
/// each instance's `palette` says).
///
/// # Safety
/// `f` is NULL or a live forest; `count` is NULL or a place for a `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_frame_palettes(
    f: *mut SylvaForest,
    count: *mut usize,
) -> *const f32 {
    // SAFETY: guaranteed by the caller.
    match unsafe { forest(f) } {
        Some(f) => array(&f.frame.palettes, count),
        None => array::<f32>(&[], count),
    }
}

/// The last frame's instances, `*count` of them, bucket by bucket.
///
/// # Safety
/// `f` is NULL or a live forest; `count` is NULL or a place for a `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_frame_instances(
    f: *mut SylvaForest,
    count: *mut usize,
) -> *const Instance {
    // SAFETY: guaranteed by the caller.
    match unsafe { forest(f) } {
        Some(f) => array(&f.frame.instances, count),
        None => array::<Instance>(&[], count),
    }
}

/// The last frame's buckets, `*count` of them.
///
/// # Safety
/// `f` is NULL or a live forest; `count` is NULL or a place for a `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_frame_buckets(
    f: *mut SylvaForest,
    count: *mut usize,
) -> *const SylvaBucket {
    // SAFETY: guaranteed by the caller.
    match unsafe { forest(f) } {
        Some(f) => array(&f.buckets, count),
        None => array::<SylvaBucket>(&[], count),
    }
}

/// The wind at world point `p` (m) now, in m/s, into `out`, as the trees feel it. Returns
/// 0, or 1 for a NULL argument.
///
/// # Safety
/// `f` is NULL or a live forest; `p` and `out` are NULL or point to three floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_forest_wind(
    f: *mut SylvaForest,
    p: *const f32,
    out: *mut f32,
) -> i32 {
    // SAFETY: guaranteed by the caller.
    let Some(f) = (unsafe { forest(f) }) else { return 1 };
    if p.is_null() || out.is_null() {
        return 1;
    }
    // SAFETY: three floats each, by the caller's guarantee.
    let (p, out) =
        unsafe { (std::slice::from_raw_parts(p, 3), std::slice::from_raw_parts_mut(out, 3)) };
    let w = f.forest.wind_sample([p[0] as f64, p[1] as f64, p[2] as f64]);
    out.copy_from_slice(&w);
    0
}

/// The size of `SylvaLeafCard` in bytes, for a host to check its declaration against.
#[unsafe(no_mangle)]
pub extern "C" fn sylva_leaf_card_size() -> usize {
    std::mem::size_of::<LeafCluster>()
}

/// The species of the forest's scene (0 for a NULL forest).
///
/// # Safety
/// `f` is NULL or a live forest.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_species_count(f: *mut SylvaForest) -> u32 {
    // SAFETY: guaranteed by the caller.
    unsafe { forest(f) }.map_or(0, |f| f.forest.species.len() as u32)
}

/// The mesh levels of `species` (0 for a NULL forest or no such species): levels
/// `0 … n − 1` are meshes, and a bucket of level `n` draws the species' impostor.
///
/// # Safety
/// `f` is NULL or a live forest.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_species_levels(f: *mut SylvaForest, species: u32) -> u32 {
    // SAFETY: guaranteed by the caller.
    unsafe { forest(f) }
        .and_then(|f| f.forest.species.get(species as usize))
        .map_or(0, |s| s.model.lods.len() as u32)
}

/// One mesh level of a species, in tree space (before an instance's yaw, scale and
/// position), in place: the branch vertices (`vertices` of them: 3 floats of position, 3
/// of normal, 2 of bark texture coordinates, 4 joint indices and 4 weights each), the
/// triangles (`indices` corners, counter-clockwise from outside) and the leaf cards. The
/// joint indices are the forest's, so an instance's palettes skin the mesh as they are.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct SylvaMesh {
    /// Branch vertices.
    pub vertices: usize,
    /// Rest positions, tree space, m: 3 floats a vertex.
    pub positions: *const f32,
    /// Unit normals: 3 floats a vertex.
    pub normals: *const f32,
    /// Bark texture coordinates: 2 floats a vertex.
    pub uvs: *const f32,
    /// Joint indices: 4 a vertex (unused slots repeat the first with weight 0).
    pub joints: *const u32,
    /// Joint weights: 4 a vertex, summing to 1.
    pub weights: *const f32,
    /// Triangle corners (3 a triangle).
    pub indices: usize,
    /// The corners' vertex indices.
    pub index: *const u32,
    /// Leaf cards.
    pub cards: usize,
    /// The cards (`SylvaLeafCard`: the Rust type `LeafCluster`).
    pub card: *const LeafCluster,
}

/// Fill `out` with mesh `level` of `species` (see `SylvaMesh`). Returns 0; 1 for a NULL
/// argument; 2 for a species or level out of range.
///
/// # Safety
/// `f` is NULL or a live forest; `out` is NULL or points to a `SylvaMesh`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_species_mesh(
    f: *mut SylvaForest,
    species: u32,
    level: u32,
    out: *mut SylvaMesh,
) -> i32 {
    // SAFETY: guaranteed by the caller.
    let (Some(f), Some(out)) = (unsafe { forest(f) }, unsafe { out.as_mut() }) else {
        fail("sylva_species_mesh: forest or out is NULL".into());
        return 1;
    };
    let Some(lod) =
        f.forest.species.get(species as usize).and_then(|s| s.model.lods.get(level as usize))
    else {
        fail(format!("sylva_species_mesh: no species {species} with a mesh level {level}"));
        return 2;
    };
    let b = &lod.branches;
    *out = SylvaMesh {
        vertices: b.positions.len(),
        positions: b.positions.as_ptr().cast(),
        normals: b.normals.as_ptr().cast(),
        uvs: b.uvs.as_ptr().cast(),
        joints: b.joints.as_ptr().cast(),
        weights: b.weights.as_ptr().cast(),
        indices: b.indices.len(),
        index: b.indices.as_ptr(),
        cards: lod.clusters.len(),
        card: lod.clusters.as_ptr(),
    };
    0
}

/// A species' texture, RGBA8 (sRGB), rows top first: `which` 0 the bark (tiling; `u` around
/// the stem, `v` along it), 1 the leaf atlas (`cells × cells` cells, a card showing cell
/// `atlas` of it, alpha the leaves' outline). Sets `*width`, `*height` and, for the
/// atlas, `*cells` (1 for the bark). NULL for a NULL forest, a species out of range or
/// another `which`.
///
/// # Safety
/// `f` is NULL or a live forest; `width`, `height` and `cells` are NULL or places for a
/// `uint32_t` each.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sylva_species_texture(
    f: *mut SylvaForest,
    species: u32,
    which: u32,
    width: *mut u32,
    height: *mut u32,
    cells: *mut u32,
) -> *const u8 {
    // SAFETY: guaranteed by the caller.
    let Some(model) =
        unsafe { forest(f) }.and_then(|f| f.forest.species.get(species as usize)).map(|s| &s.model)
    else {
        fail(format!("sylva_species_texture: no forest or no species {species}"));
        return std::ptr::null();
    };
    let (image, n) = match which {
        0 => (&model.bark, 1),
        1 => (&model.leaves.image, model.leaves.cells),
        _ => {
            fail(format!("sylva_species_texture: which {which}: 0 (bark) or 1 (leaves)"));
            return std::ptr::null();
        }
    };
    for (place, v) in [(width, image.width), (height, image.height), (cells, n)] {
        if !place.is_null() {
            // SAFETY: checked non-NULL; the caller passes a place for a `uint32_t`.
            unsafe { *place = v };
        }
    }
    image.rgba.as_ptr()
}
