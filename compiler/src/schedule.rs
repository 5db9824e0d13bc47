//! Phase `schedule`, between `pack` and `codegen`: the schedule each live Map, Filter,
//! Mipmap and Shade pass runs in, chosen once. A pass runs in the schedule its technique
//! or `--schedule` asks for, except where its compute form cannot be generated: then it
//! runs as fragment (forward, for Shade) and the reason is recorded ([`compute_refusal`],
//! [`shade_refusal`]). Codegen generates the chosen form and `explain` reports it, with
//! the reason, from the same [`Schedules`].

use crate::builtins::{Input, SampleFn};
use crate::front::ast::Schedule;
use crate::handle::Table;
use crate::ir::{IrKernel, IrPass, IrPassKind, Node, PassId, Program, Texture};
use crate::pack::{scratch_precision, texture_format};
use sshc_graph as graph;

/// How a pass with schedules to choose from runs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Choice {
    /// The fragment schedule (forward, for Shade), as asked.
    Fragment,
    /// The compute schedule (deferred, for Shade), as asked.
    Compute,
    /// The fragment schedule, the compute one asked for being refused for this reason.
    Refused(String),
}

impl Choice {
    /// The schedule the pass runs in.
    pub fn runs(&self) -> Schedule {
        match self {
            Choice::Fragment | Choice::Refused(_) => Schedule::Fragment,
            Choice::Compute => Schedule::Compute,
        }
    }
}

/// The choice of every pass: `None` for a pass that dead-code elimination removed and for
/// the kinds with one schedule (Depth, SummedArea, Geometry).
#[derive(Clone, Debug, Default)]
pub struct Schedules {
    passes: Table<Option<Choice>, IrPass>,
}

impl Schedules {
    /// How pass `p` runs, where it has schedules to choose from and is live.
    pub fn of(&self, p: PassId) -> Option<&Choice> {
        self.passes.get(p).and_then(Option::as_ref)
    }

    /// Whether pass `p` runs in the compute schedule.
    pub fn compute(&self, p: PassId) -> bool {
        self.of(p).is_some_and(|c| c.runs().is_compute())
    }

    /// The text of `--dump-ir-after schedule`: every pass, in execution order, with the
    /// schedule it runs in and, where the compute one asked for was refused, why.
    pub fn dump(&self, ir: &Program) -> String {
        let mut s = format!("technique {}: schedules\n", ir.technique);
        for (pi, pass) in ir.passes.with_handles() {
            let shade = pass.kind.kind().is_shade();
            let form = |runs: Schedule| match (runs, shade) {
                (Schedule::Fragment, true) => "fragment (forward)",
                (Schedule::Compute, true) => "compute (deferred)",
                (runs, false) => runs.name(),
            };
            let how = match self.of(pi) {
                None if !pass.live => "removed by dead-code elimination".to_string(),
                None => "the one schedule of its kind".to_string(),
                Some(c @ (Choice::Fragment | Choice::Compute)) => format!("{}, as asked", form(c.runs())),
                Some(Choice::Refused(why)) => format!("{}; {} was asked for, but {why}", form(Schedule::Fragment), form(Schedule::Compute)),
            };
            s.push_str(&format!("  pass {} ({}): {how}\n", pass.name, pass.kind_name()));
        }
        s
    }
}

/// The schedule of every live pass of `ir`.
pub fn choose(ir: &Program) -> Schedules {
    Schedules {
        passes: ir.passes.iter().map(|p| if p.live { choice(ir, p) } else { None }).collect(),
    }
}

/// How `pass` runs: as asked, unless the compute schedule is asked for and refused.
fn choice(ir: &Program, pass: &IrPass) -> Option<Choice> {
    let refusal = match pass.kind {
        IrPassKind::Map | IrPassKind::Filter { .. } | IrPassKind::Mipmap { .. } => compute_refusal,
        IrPassKind::Shade { .. } => shade_refusal,
        IrPassKind::Depth { .. } | IrPassKind::SummedArea { .. } | IrPassKind::Geometry { .. } => return None,
    };
    Some(match pass.schedule {
        Schedule::Fragment => Choice::Fragment,
        Schedule::Compute => match refusal(ir, pass) {
            None => Choice::Compute,
            Some(why) => Choice::Refused(why),
        },
    })
}

/// A Filter's workgroup tile in the compute schedule: (apron x, apron y, width, height) in
/// texels for a workgroup of [`graph::TEXEL_WORKGROUP`] squared invocations, on one axis
/// of a separable kernel (`horizontal`) or both (the 3 x 3 LoG).
pub fn filter_tile(kernel: &IrKernel, horizontal: bool) -> (i32, i32, i32, i32) {
    let r = (kernel.size() as i32 - 1) / 2;
    let (ax, ay) = match (kernel.separable(), horizontal) {
        (false, _) => (r, r),
        (true, true) => (r, 0),
        (true, false) => (0, r),
    };
    let g = graph::TEXEL_WORKGROUP as i32;
    (ax, ay, g + 2 * ax, g + 2 * ay)
}

/// WebGPU's guaranteed workgroup memory (`maxComputeWorkgroupStorageSize`), bytes.
const WORKGROUP_MEMORY: u32 = 16384;

/// Why a Map, Filter or Mipmap pass that asks for the compute schedule runs as fragment, or None:
/// a written format that is not a storage format, or a Filter's tile and apron that do not
/// fit WebGPU's workgroup memory.
pub fn compute_refusal(ir: &Program, pass: &IrPass) -> Option<String> {
    let w = pass.writes?;
    let mut formats: Vec<graph::Format> = ir.resources[w].textures.iter().map(texture_format).collect();
    if let IrPassKind::Filter { kernel } = &pass.kind {
        if kernel.separable() {
            formats.extend(ir.resources[w].textures.iter().map(|t| {
                texture_format(&Texture {
                    precision: scratch_precision(t.precision),
                    ..t.clone()
                })
            }));
        }
        let bytes = [true, false]
            .iter()
            .map(|&h| {
                let (_, _, tw, th) = filter_tile(kernel, h);
                (tw * th * 16) as u32
            })
            .max()
            .unwrap_or(0);
        if bytes > WORKGROUP_MEMORY {
            return Some(format!(
                "its tile and apron need {bytes} bytes of workgroup memory, above WebGPU's {WORKGROUP_MEMORY}"
            ));
        }
    }
    let mut bad: Vec<String> = formats.iter().filter(|f| !f.storable()).map(|f| format!("{f:?}")).collect();
    bad.dedup();
    (!bad.is_empty()).then(|| format!("{} is not a storage format", bad.join(" and ")))
}

/// Why a Shade pass that asks for the compute (deferred) schedule runs forward, or None:
/// what the G-buffer does not carry, the screen-space derivatives of a light sample's view
/// (its `depth_slope`, the footprint of its implicit-LOD `sample`).
pub fn shade_refusal(ir: &Program, pass: &IrPass) -> Option<String> {
    let visibility = pass.kind.visibility()?;
    let arena = &ir.ir.arena;
    // the per-sample lookups and inputs
    arena.postorder(&ir.shade_roots(visibility)).into_iter().find_map(|h| {
        if let Node::Input(Input::DepthSlope, Some(k)) = arena.node(h) {
            return Some(format!(
                "it reads `depth_slope` in light sample {k}'s view, and the G-buffer carries the centre view's only"
            ));
        }
        if let Node::Sample {
            how: SampleFn::Sample,
            view: Some(k),
            ..
        } = arena.node(h)
        {
            return Some(format!(
                "its `sample` in light sample {k}'s view needs that view's screen-space footprint, and the G-buffer carries the centre view's only"
            ));
        }
        None
    })
}
