//! Phase `codegen`: one WGSL module per live pass, following the binding conventions of
//! `sshc_graph`, in the schedule the `schedule` phase chose; each pass kind has its
//! emitter (`back/depth.rs`, `map.rs`, `geometry_pass.rs`, `filter.rs`, `mipmap.rs`,
//! `summed_area.rs`, `shade.rs`), expressions go through the emitter of `back/expr.rs`.
//! Every module is validated with naga inside the compiler, and each entry point's
//! operations are counted on naga's IR.

use crate::back::depth::depth;
use crate::back::filter::filter;
use crate::back::geometry_pass::{geometry, geometry_buffers};
use crate::back::map::map;
use crate::back::mipmap::mipmap;
use crate::back::parts::Split;
use crate::back::shade::shade;
use crate::back::summed_area::summed_area;
use crate::back::{self, internal};
use crate::diag::Diagnostics;
use crate::ir::{IrPassKind, PassId, Program};
use crate::pack::Limits;
use crate::schedule::Schedules;
use sshc_graph::{self as graph, Step};

pub use crate::back::filter::Scratch;
pub use crate::back::text::params_struct;

/// One generated module and the steps that run it.
#[derive(Clone, Debug)]
pub struct Module {
    pub pass: PassId,
    pub file: String,
    pub source: String,
    pub steps: Vec<Step>,
    /// Buffers its steps generate on the GPU (Geometry passes).
    pub buffers: Vec<graph::BufferDecl>,
}

/// What codegen produces: one module per live pass, in pass order, and the scratch
/// textures they need.
pub struct Output {
    pub modules: Vec<Module>,
    pub scratch: Vec<Scratch>,
}

/// Generate and validate the module of every live pass, each in the schedule `schedules`
/// chose for it.
pub fn codegen(ir: &Program, schedules: &Schedules, limits: &Limits, split: Split) -> Result<Output, Diagnostics> {
    let mut modules = Vec::new();
    let mut scratch = Vec::new();
    let mut diags = Diagnostics::default();
    for (pi, pass) in ir.passes.with_handles() {
        if !pass.live {
            continue;
        }
        let file = format!("{}.{}.wgsl", ir.technique, pass.name);
        let compute = schedules.compute(pi);
        let r = match &pass.kind {
            IrPassKind::Depth { .. } => depth(ir, pass),
            IrPassKind::Map => map(ir, pass, compute, limits, split),
            IrPassKind::Filter { kernel } => filter(ir, pass, kernel, compute, limits, &mut scratch),
            IrPassKind::Mipmap { reduce } => mipmap(ir, pass, *reduce, compute, limits),
            IrPassKind::Shade { visibility } => shade(ir, pass, *visibility, compute, split),
            IrPassKind::SummedArea { .. } => summed_area(ir, pass),
            IrPassKind::Geometry {
                primitive, resolve, keep, ..
            } => geometry(ir, pass, *primitive, *resolve, *keep, limits, split),
        };
        match r {
            Ok((source, steps)) => {
                let buffers = geometry_buffers(pass, &steps);
                modules.push(Module {
                    pass: pi,
                    file,
                    source,
                    steps,
                    buffers,
                })
            }
            Err(d) => diags.push(d),
        }
    }
    diags.check()?;
    // the helper functions the code calls
    for m in &mut modules {
        if m.source.contains("sshc_noise(") {
            m.source.push_str(crate::builtins::NOISE_WGSL);
        }
    }
    validate_all(&mut modules)?;
    Ok(Output { modules, scratch })
}

/// Parse and validate every module with naga, and count each entry point's operations.
fn validate_all(modules: &mut [Module]) -> Result<(), Diagnostics> {
    let mut diags = Diagnostics::default();
    for m in modules.iter_mut() {
        match back::validate(&m.source) {
            Ok(module) => {
                for step in &mut m.steps {
                    let entry = step.fragment.clone().or_else(|| step.compute.clone());
                    if let Some(e) = entry {
                        step.cost = back::count_ops(&module, &e);
                    }
                }
            }
            Err(msg) => diags.push(internal(format!("generated WGSL for `{}` does not validate: {msg}", m.file))),
        }
    }
    diags.check()
}
