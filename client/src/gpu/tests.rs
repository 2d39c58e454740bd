//! Tests of the generated WGSL: every pass validates with naga over whole and split
//! buffers (and over the browser page's one world binding within WebGPU's default limits),
//! declares no uniform buffer and lays its shared structs out as Rust does; the
//! prelude's constants read back with the Rust bits and its accessors pick the part.

use super::baseline::taa_pass;
use super::bindings::Split;
use super::gi::{GiPass, GiSplit, gi_pass};
use super::irradiance::{irradiance_sample_pass, irradiance_update_pass};
use super::params::{
    FrameInfo, GiInfo, IrradianceInfo, LightInfo, RayCount, RayIn, RomaInfo, RomaJob, RomaWindow, View, WgslStruct,
    WorldInfo,
};
use super::pathtrace::path_pass;
use super::rays::rays_pass;
use super::render::render_pass;
use super::roma::{roma_build_pass, roma_sample_pass};
use super::shaders::{CONSTANTS, Loop, PassSource, WgslValue, WorldBindings, prelude, source};

fn validate(src: &str) -> Result<(), String> {
    let module = naga::front::wgsl::parse_str(src).map_err(|e| e.emit_to_string(src))?;
    // The capabilities wgpu grants on every backend the client targets; the browser has
    // them too (WebGPU's core `pack2x16float`).
    let caps = naga::valid::Capabilities::SHADER_FLOAT16_IN_FLOAT32;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
        .validate(&module)
        .map_err(|e| e.emit_to_string(src))?;
    Ok(())
}

fn parse(src: &str) -> naga::Module {
    naga::front::wgsl::parse_str(src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(src)))
}

/// Every buffer in one binding.
fn whole() -> Split {
    Split {
        part_shift: 25,
        parts: [1; 8],
    }
}

/// Every pass: the ray list, the frame, the two path-tracing entry points, the TAA
/// resolve, ROMA's sample and build passes, the irradiance cache's sample and update
/// passes, and the GI passes over `gi_split`.
fn every_pass(gi_split: GiSplit) -> Vec<PassSource> {
    let mut passes = vec![
        rays_pass(),
        render_pass(),
        path_pass("path_trace"),
        path_pass("path_sample"),
        taa_pass(),
        roma_sample_pass(),
        roma_build_pass(),
        irradiance_sample_pass(),
        irradiance_update_pass("irradiance_invalidate"),
        irradiance_update_pass("irradiance_args"),
        irradiance_update_pass("irradiance_update"),
    ];
    passes.extend(GiPass::ALL.map(|p| gi_pass(p, gi_split)));
    passes
}

#[test]
fn every_pass_validates_with_naga_for_whole_and_split_buffers() {
    let split = Split {
        part_shift: 14,
        parts: [2, 1, 3, 4, 1, 1, 2, 5],
    };
    let gi_whole = GiSplit {
        part_bytes_shift: 27,
        mem_parts: 1,
        taa_parts: 1,
    };
    let gi_split = GiSplit {
        part_bytes_shift: 16,
        mem_parts: 3,
        taa_parts: 2,
    };
    for (s, g) in [(whole(), gi_whole), (split, gi_split)] {
        for pass in every_pass(g) {
            for lp in Loop::ALL {
                if let Err(e) = validate(&source(&pass, lp, WorldBindings::Split(&s))) {
                    panic!("{} with {lp:?} over {s:?}:\n{e}", pass.entry);
                }
            }
        }
    }
}

/// The browser page's form of every pass (the GI pipeline's too): the world in one storage
/// binding and the parameters as uniforms validate (with `unpack2x16float`, core in WebGPU,
/// as the only capability naga asks for) within
/// WebGPU's default 8 storage buffers per stage.
#[test]
fn every_pass_fits_webgpu_default_limits_over_one_world_binding() {
    let gi_whole = GiSplit {
        part_bytes_shift: 27,
        mem_parts: 1,
        taa_parts: 1,
    };
    for pass in every_pass(gi_whole) {
        let wgsl = source(&pass, Loop::Hierarchy, WorldBindings::Single);
        if let Err(e) = validate(&wgsl) {
            panic!("{}:\n{e}", pass.entry);
        }
        let module = parse(&wgsl);
        let storage = module
            .global_variables
            .iter()
            .filter(|(_, v)| matches!(v.space, naga::AddressSpace::Storage { .. }))
            .count();
        assert!(storage <= 8, "{} declares {storage} storage buffers", pass.entry);
    }
}

/// Lavapipe re-optimises a shader for the values of its uniform buffers at every
/// dispatch (see `Gpu::params`), so no pass may declare one.
#[test]
fn no_pass_declares_a_uniform_buffer() {
    let gi_split = GiSplit {
        part_bytes_shift: 27,
        mem_parts: 1,
        taa_parts: 1,
    };
    for pass in every_pass(gi_split) {
        for lp in Loop::ALL {
            let module = parse(&source(&pass, lp, WorldBindings::Split(&whole())));
            let uniforms: Vec<_> = module
                .global_variables
                .iter()
                .filter(|(_, v)| v.space == naga::AddressSpace::Uniform)
                .map(|(_, v)| v.name.clone().unwrap_or_default())
                .collect();
            assert!(
                uniforms.is_empty(),
                "{} with {lp:?} declares uniform buffers {uniforms:?}",
                pass.entry
            );
        }
    }
}

/// Checks that `module` lays `T` out at the Rust offsets and size.
fn assert_rust_layout<T: WgslStruct>(module: &naga::Module) {
    let (members, span) = module
        .types
        .iter()
        .find_map(|(_, t)| match &t.inner {
            naga::TypeInner::Struct { members, span } if t.name.as_deref() == Some(T::NAME) => Some((members, *span)),
            _ => None,
        })
        .unwrap_or_else(|| panic!("the module declares {}", T::NAME));
    let wgsl: Vec<(&str, usize)> = members
        .iter()
        .map(|m| (m.name.as_deref().unwrap_or_default(), m.offset as usize))
        .collect();
    let rust: Vec<(&str, usize)> = T::MEMBERS.iter().map(|m| (m.name, m.offset)).collect();
    assert_eq!(wgsl, rust, "{}", T::NAME);
    assert_eq!(span as usize, size_of::<T>(), "{}", T::NAME);
}

#[test]
fn the_shared_structs_are_laid_out_at_the_rust_offsets() {
    let prelude = parse(&source(&taa_pass(), Loop::Hierarchy, WorldBindings::Split(&whole())));
    assert_rust_layout::<WorldInfo>(&prelude);
    assert_rust_layout::<FrameInfo>(&prelude);
    assert_rust_layout::<LightInfo>(&prelude);
    assert_rust_layout::<GiInfo>(&prelude);
    assert_rust_layout::<View>(&parse(&source(
        &render_pass(),
        Loop::Hierarchy,
        WorldBindings::Split(&whole()),
    )));
    let rays = parse(&source(&rays_pass(), Loop::Hierarchy, WorldBindings::Split(&whole())));
    assert_rust_layout::<RayCount>(&rays);
    assert_rust_layout::<RayIn>(&rays);
    let roma = parse(&source(
        &roma_build_pass(),
        Loop::Hierarchy,
        WorldBindings::Split(&whole()),
    ));
    assert_rust_layout::<RomaInfo>(&roma);
    assert_rust_layout::<RomaWindow>(&roma);
    assert_rust_layout::<RomaJob>(&roma);
    let irradiance = parse(&source(
        &irradiance_update_pass("irradiance_update"),
        Loop::Hierarchy,
        WorldBindings::Split(&whole()),
    ));
    assert_rust_layout::<IrradianceInfo>(&irradiance);
}

/// The value naga reads for a constant's initialiser.
fn value(module: &naga::Module, e: naga::Handle<naga::Expression>) -> WgslValue {
    let scalar = |e: naga::Handle<naga::Expression>| match module.global_expressions[e] {
        naga::Expression::Literal(naga::Literal::F32(v)) => v,
        ref e => panic!("not an f32 literal: {e:?}"),
    };
    match module.global_expressions[e] {
        naga::Expression::Literal(naga::Literal::U32(v)) => WgslValue::U32(v),
        naga::Expression::Literal(naga::Literal::I32(v)) => WgslValue::I32(v),
        naga::Expression::Literal(naga::Literal::F32(v)) => WgslValue::F32(v),
        naga::Expression::Compose { ref components, .. } if components.len() == 3 => {
            WgslValue::Vec3(scalar(components[0]), scalar(components[1]), scalar(components[2]))
        }
        ref e => panic!("not a constant of the prelude's types: {e:?}"),
    }
}

/// WGSL reads back every constant bit for bit: the same bits as the Rust item.
#[test]
fn the_prelude_constants_have_their_rust_values_bit_for_bit() {
    let module = parse(&prelude(WorldBindings::Split(&whole())));
    let wgsl: Vec<(&str, WgslValue)> = module
        .constants
        .iter()
        .map(|(_, c)| (c.name.as_deref().unwrap_or_default(), value(&module, c.init)))
        .collect();
    let bits = |v: WgslValue| match v {
        WgslValue::U32(v) => vec![v],
        WgslValue::I32(v) => vec![v as u32],
        WgslValue::F32(v) => vec![v.to_bits()],
        WgslValue::Vec3(x, y, z) => vec![x.to_bits(), y.to_bits(), z.to_bits()],
    };
    let wgsl: Vec<_> = wgsl.into_iter().map(|(n, v)| (n, bits(v))).collect();
    let rust: Vec<_> = CONSTANTS.iter().map(|&(n, v)| (n, bits(v))).collect();
    assert_eq!(wgsl, rust);
}

#[test]
fn split_accessors_pick_the_part() {
    let p = prelude(WorldBindings::Split(&Split {
        part_shift: 14,
        parts: [1, 1, 3, 1, 1, 1, 1, 1],
    }));
    assert!(p.contains("fn voxel_word(i: u32) -> u32 {\n    let j = i & 16383u;\n    switch i >> 14u {"));
    assert!(p.contains("case 1u: { return voxels_1[j]; }"));
    assert!(p.contains("default: { return voxels_2[j]; }"));
    assert!(p.contains("fn chunk_word(i: u32) -> u32 { return chunks_0[i]; }"));
}
