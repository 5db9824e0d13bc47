//! Phase `emit`: the pass graph (the runtime crate's versioned schema) and the WGSL files.
//! Its cost report ([`Cost`]: bytes per texel of every resource, fetches and operations
//! per invocation of every step, counted on the naga IR) is the schema crate's cost model
//! (`sshc_graph::cost`) applied to that graph.

use crate::back::wgsl::Output;
use crate::front::ast::{ConstValue, LightView, ScalarTy};
use crate::ir::*;
use crate::pack::{mip_source, table_source, texture_format};
pub use sshc_graph::cost::Cost;
use sshc_graph::{self as graph, ChannelDecl, Extent, ParamDecl, ParamType, PassDecl, PassGraph, TextureDecl, Views};

pub fn graph(ir: &Program, out: &Output) -> PassGraph {
    let mut params = Vec::new();
    let mut offset = 0u32;
    for p in &ir.params {
        let ty = match p.ty {
            ScalarTy::F32 => ParamType::F32,
            ScalarTy::I32 => ParamType::I32,
            ScalarTy::Bool => ParamType::Bool,
        };
        let value = match p.value {
            ConstValue::Bool(b) => b as i32 as f64,
            v @ (ConstValue::Int(_) | ConstValue::Uint(_) | ConstValue::Float(_)) => v.as_f64(),
        };
        let off = if p.uniform {
            offset += 4;
            Some(offset - 4)
        } else {
            None
        };
        params.push(ParamDecl {
            name: p.name.clone(),
            ty,
            value,
            range: p.range,
            offset: off,
            doc: p.doc.clone(),
        });
    }
    let params_size = offset.div_ceil(16) * 16;

    let mut textures: Vec<TextureDecl> = Vec::new();
    for (ri, r) in ir.resources.with_handles().filter(|(_, r)| r.live) {
        let mips = mip_source(ir, ri).is_some();
        let table = table_source(ir, ri).is_some();
        for (ti, t) in r.textures.iter().enumerate() {
            if let Some(existing) = textures.iter_mut().find(|d| d.name == t.name) {
                existing.mips |= mips;
                continue;
            }
            let channels = r
                .slots
                .iter()
                .filter(|s| s.texture == ti)
                .map(|s| ChannelDecl {
                    name: ir.channels[s.channel].name.clone(),
                    layer: s.layer,
                    component: s.component,
                    bias: s.encode.bias,
                    scale: s.encode.scale,
                    range: (s.range.lo, s.range.hi),
                })
                .collect();
            textures.push(TextureDecl {
                name: t.name.clone(),
                format: match table {
                    false => texture_format(t),
                    // codegen has read every table's code (`table_code` fails on no table)
                    true if matches!(
                        crate::back::summed_area::table_code(ir, ri, ti),
                        Ok(crate::back::summed_area::TableCode::Float)
                    ) =>
                    {
                        graph::Format::SummedAreaF32
                    }
                    true => graph::Format::SummedAreaU32,
                },
                layers: t.layers,
                extent: Extent::ShadowMap,
                mips,
                transient: false,
                channels,
                views: if ir.per_sample(ri) { ir.samples } else { 1 },
            });
        }
    }
    for s in &out.scratch {
        if let Some(like) = textures.iter().find(|t| t.name == s.like).cloned()
            && !textures.iter().any(|t| t.name == s.name)
        {
            textures.push(TextureDecl {
                name: s.name.clone(),
                format: s.format,
                mips: false,
                transient: true,
                channels: vec![],
                ..like
            });
        }
    }
    // the Shade's debug outputs: camera-sized, one layer, unencoded
    for d in &ir.debug {
        let ty = ir.arena.ty(d.expr);
        let components = crate::back::shade::debug_components(ty);
        textures.push(TextureDecl {
            name: d.texture.clone(),
            format: crate::back::shade::debug_format(ty),
            layers: 1,
            extent: Extent::Camera,
            mips: false,
            transient: false,
            channels: (0..components)
                .map(|component| ChannelDecl {
                    name: if components == 1 {
                        d.name.clone()
                    } else {
                        format!("{}.{}", d.name, ["x", "y", "z", "w"][component as usize])
                    },
                    layer: 0,
                    component,
                    bias: 0.0,
                    scale: 1.0,
                    // any f32: the value is stored as computed
                    range: (-f64::from(f32::MAX), f64::from(f32::MAX)),
                })
                .collect(),
            views: 1,
        });
    }
    let passes = out
        .modules
        .iter()
        .map(|m| PassDecl {
            name: ir.passes[m.pass].name.clone(),
            kind: ir.passes[m.pass].kind.kind(),
            views: match ir.passes[m.pass].kind {
                IrPassKind::Depth {
                    view: LightView::PerSample,
                }
                | IrPassKind::Geometry {
                    view: LightView::PerSample,
                    ..
                } => Views::PerLightSample,
                IrPassKind::Depth { .. }
                | IrPassKind::Map
                | IrPassKind::Filter { .. }
                | IrPassKind::Mipmap { .. }
                | IrPassKind::SummedArea { .. }
                | IrPassKind::Geometry { .. }
                | IrPassKind::Shade { .. } => Views::LightCenter,
            },
            shader: m.file.clone(),
            steps: m.steps.clone(),
        })
        .collect();
    PassGraph {
        version: graph::SCHEMA_VERSION,
        technique: ir.technique.clone(),
        title: ir.title.clone(),
        paper: ir.paper.clone(),
        lights: ir.lights.clone(),
        params,
        params_size,
        textures,
        samples: ir.samples,
        buffers: out.modules.iter().flat_map(|m| m.buffers.iter().cloned()).collect(),
        passes,
        removed: ir.removed.to_vec(),
        specialised: ir.ir.specialised.as_ref().map(|s| s.facts.clone()),
        shadow_map: ir.ir.shadow_map,
    }
}
