//! Rust ↔ WGSL layouts: every struct the shaders read has the size and field offsets naga
//! computes for its WGSL twin, and every vertex attribute the type its shader input has at
//! that location (CPU only, no GPU).

use std::mem::{offset_of, size_of};

use naga::{Module, ScalarKind, TypeInner, VectorSize};
use sylva_forest::Instance;
use sylva_render::layout::{
    BRANCH_ATTRIBUTES, BranchVertex, FAR_INSTANCE_ATTRIBUTES, FarSpecies, GROUND_ATTRIBUTES,
    Globals, GroundVertex, INSTANCE_ATTRIBUTES, LEAF_ATTRIBUTES, LeafVertex,
};
use sylva_render::shader_source;
use sylva_render::wgpu::{self, VertexFormat};

fn module(file: &str) -> Module {
    let src = shader_source(file).expect("shader");
    naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{file}: {e}"))
}

/// (size, [(member, offset)]) of WGSL struct `name`.
fn wgsl_struct(m: &Module, name: &str) -> (u32, Vec<(String, u32)>) {
    let (_, ty) = m
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name}"));
    match &ty.inner {
        TypeInner::Struct { members, span } => (
            *span,
            members.iter().map(|mb| (mb.name.clone().unwrap_or_default(), mb.offset)).collect(),
        ),
        other => panic!("{name} is {other:?}"),
    }
}

fn check_struct(file: &str, name: &str, size: usize, fields: &[(&str, usize)]) {
    let (span, members) = wgsl_struct(&module(file), name);
    assert_eq!(span as usize, size, "{name}: WGSL size {span}, Rust {size}");
    assert_eq!(members.len(), fields.len(), "{name}: member count");
    for ((wname, woff), (rname, roff)) in members.iter().zip(fields) {
        assert_eq!(wname, rname, "{name}: member order");
        assert_eq!(*woff as usize, *roff, "{name}.{wname}: WGSL offset {woff}, Rust {roff}");
    }
}

#[test]
fn globals_match_their_wgsl_twin() {
    macro_rules! f {
        ($($n:ident),*) => { [$((stringify!($n), offset_of!(Globals, $n))),*] };
    }
    let fields = f!(
        view_proj,
        inv_view_proj,
        eye,
        time,
        sun_dir,
        fog_density,
        sun_colour,
        sun_intensity,
        ambient_sky,
        pad2,
        ambient_ground,
        pad3,
        sky_zenith,
        pad4,
        sky_horizon,
        exposure,
        sun_view_proj,
        shadow_texel,
        overlay,
        pad6,
        pad7,
        sun_view_proj_far
    );
    check_struct("common.wgsl", "Globals", size_of::<Globals>(), &fields);
}

#[test]
fn impostor_parameters_match_their_wgsl_twin() {
    macro_rules! f {
        ($($n:ident),*) => { [$((stringify!($n), offset_of!(FarSpecies, $n))),*] };
    }
    let fields = f!(
        tip,
        extent,
        center,
        views,
        joint,
        rows,
        radius,
        height,
        row_step,
        depth_range,
        crown,
        outline
    );
    check_struct("far.wgsl", "FarSpecies", size_of::<FarSpecies>(), &fields);
}

fn type_name(inner: &TypeInner) -> String {
    let scalar = |k: ScalarKind| match k {
        ScalarKind::Float => "f32",
        ScalarKind::Uint => "u32",
        ScalarKind::Sint => "i32",
        _ => "?",
    };
    match inner {
        TypeInner::Scalar(s) => scalar(s.kind).to_string(),
        TypeInner::Vector { size, scalar: s } => {
            let n = match size {
                VectorSize::Bi => 2,
                VectorSize::Tri => 3,
                VectorSize::Quad => 4,
            };
            format!("vec{n}<{}>", scalar(s.kind))
        }
        other => format!("{other:?}"),
    }
}

fn format_name(f: VertexFormat) -> &'static str {
    match f {
        VertexFormat::Float32 => "f32",
        VertexFormat::Float32x2 | VertexFormat::Float16x2 => "vec2<f32>",
        VertexFormat::Float32x3 => "vec3<f32>",
        VertexFormat::Float32x4 => "vec4<f32>",
        VertexFormat::Uint32 => "u32",
        VertexFormat::Uint32x2 => "vec2<u32>",
        VertexFormat::Uint32x4 => "vec4<u32>",
        _ => "unexpected",
    }
}

/// Location → WGSL type of the members of input struct `name`.
fn inputs(m: &Module, name: &str) -> Vec<(u32, String)> {
    let (_, ty) = m.types.iter().find(|(_, t)| t.name.as_deref() == Some(name)).expect("struct");
    let TypeInner::Struct { members, .. } = &ty.inner else { panic!("{name} not a struct") };
    members
        .iter()
        .filter_map(|mb| match mb.binding {
            Some(naga::Binding::Location { location, .. }) => {
                Some((location, type_name(&m.types[mb.ty].inner)))
            }
            _ => None,
        })
        .collect()
}

fn check_attributes(file: &str, input: &str, attrs: &[wgpu::VertexAttribute], stride: usize) {
    let want = inputs(&module(file), input);
    assert_eq!(want.len(), attrs.len(), "{input}: attribute count");
    for (loc, ty) in want {
        let a = attrs
            .iter()
            .find(|a| a.shader_location == loc)
            .unwrap_or_else(|| panic!("{input}: no attribute at location {loc}"));
        assert_eq!(format_name(a.format), ty, "{input} @location({loc})");
        assert!(
            a.offset as usize + a.format.size() as usize <= stride,
            "{input} @location({loc}) reads past the vertex"
        );
    }
}

#[test]
fn vertex_attributes_match_the_shader_inputs() {
    check_attributes("branch.wgsl", "BranchIn", &BRANCH_ATTRIBUTES, size_of::<BranchVertex>());
    check_attributes("leaf.wgsl", "LeafIn", &LEAF_ATTRIBUTES, size_of::<LeafVertex>());
    check_attributes("ground.wgsl", "GroundIn", &GROUND_ATTRIBUTES, size_of::<GroundVertex>());
    check_attributes("common.wgsl", "InstanceIn", &INSTANCE_ATTRIBUTES, size_of::<Instance>());
    // The impostors read the instance as the meshes do, and the crown's lean besides.
    assert_eq!(FAR_INSTANCE_ATTRIBUTES[..6], INSTANCE_ATTRIBUTES);
    check_attributes("far.wgsl", "LeanIn", &FAR_INSTANCE_ATTRIBUTES[6..], size_of::<Instance>());
}

#[test]
fn instance_fields_read_together_are_adjacent() {
    // `base` = position then yaw; `leaf` = phase then amplitude (one attribute each).
    assert_eq!(offset_of!(Instance, yaw), offset_of!(Instance, position) + 12);
    assert_eq!(offset_of!(Instance, leaf_amplitude), offset_of!(Instance, leaf_phase) + 4);
    assert_eq!(size_of::<Instance>(), 60);
}

#[test]
fn a_moved_field_is_caught() {
    // The struct check must be able to fail: Globals with a field out of place.
    let (_, members) = wgsl_struct(&module("common.wgsl"), "Globals");
    let eye = members.iter().find(|(n, _)| n == "eye").expect("eye").1 as usize;
    assert_ne!(eye, offset_of!(Globals, time));
    let r = std::panic::catch_unwind(|| {
        check_struct("common.wgsl", "Globals", size_of::<Globals>(), &[("view_proj", 4)])
    });
    assert!(r.is_err());
}
