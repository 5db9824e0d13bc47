//! Phase `codegen`: one WGSL module per GPU pass, following the binding conventions of
//! `sshc_graph`. Expressions are emitted as straight-line code in operand order,
//! one `let` per shared operation (the arena already merged equal sub-expressions), and
//! texture reads of one texel of one layer are fetched once and shared by its channels.
//! Every module is validated with naga inside the compiler.

use crate::back::geometry;
use crate::back::parts::{self, Line, Split};
use crate::builtins::{Input, SampleFn, SampleWgsl, Sig, Ty};
use crate::diag::{Diagnostic, Diagnostics, Phase};
use crate::front::ast::{ConstValue, LightView, Precision, Primitive, Reduce, Resolve, Schedule};
use crate::front::expr::{BinOp, UnOp};
use crate::ir::*;
use crate::pack::{Limits, layers_per_subpass, table_source};
use sshc_graph::{self as graph, Binding, Draw, FRAME_WGSL, OpCount, Step, Target, View};
use std::collections::HashMap;
use std::fmt::Write as _;

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

/// Intermediate textures a module needs besides the IR's (the separable filters' scratch).
#[derive(Clone, Debug)]
pub struct Scratch {
    pub name: String,
    pub like: String,
    pub format: graph::Format,
}

/// The precision of a separable filter's intermediate: wide enough that the first axis's
/// result is not rounded to the destination's precision before the second axis.
pub fn scratch_precision(p: Precision) -> Precision {
    match p {
        Precision::Unorm8 => Precision::F16,
        Precision::Unorm16 | Precision::F16 | Precision::F32 => Precision::F32,
    }
}

pub struct Output {
    pub modules: Vec<Module>,
    pub scratch: Vec<Scratch>,
}

pub fn texture_format(t: &Texture) -> graph::Format {
    use graph::Format::*;
    match (t.precision, t.components) {
        (Precision::Unorm8, 1) => R8Unorm,
        (Precision::Unorm8, 2) => Rg8Unorm,
        (Precision::Unorm8, _) => Rgba8Unorm,
        (Precision::Unorm16, 1) => R16Unorm,
        (Precision::Unorm16, 2) => Rg16Unorm,
        (Precision::Unorm16, _) => Rgba16Unorm,
        (Precision::F16, 1) => R16Float,
        (Precision::F16, 2) => Rg16Float,
        (Precision::F16, _) => Rgba16Float,
        (Precision::F32, 1) => R32Float,
        (Precision::F32, 2) => Rg32Float,
        (Precision::F32, _) => Rgba32Float,
    }
}

/// Format an f32 constant as a WGSL literal.
pub fn f32_lit(v: f32) -> String {
    if v == 0.0 {
        return "0.0f".into();
    }
    let s = if v == v.trunc() && v.abs() < 1e9 {
        format!("{v:.1}")
    } else {
        format!("{v:e}")
    };
    if v < 0.0 { format!("({s}f)") } else { format!("{s}f") }
}

fn i32_lit(v: i32) -> String {
    if v == i32::MIN {
        "(-2147483647i - 1i)".into()
    } else if v < 0 {
        format!("({v}i)")
    } else {
        format!("{v}i")
    }
}

const COMP: [char; 4] = ['x', 'y', 'z', 'w'];

/// Where expressions are evaluated.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Site {
    /// Per shadow-map texel (`texel` is the integer coordinate).
    Map,
    /// Per fragment of a Geometry pass's primitives (`texel` is the fragment's shadow-map
    /// texel; the geometry inputs are `in_*` locals).
    Geometry,
    /// Per camera pixel in the Shade pass.
    Receiver,
}

/// Emits straight-line WGSL for a set of expression roots.
struct Emitter<'a> {
    ir: &'a Program<'a>,
    site: Site,
    body: Vec<Line>,
    /// What the code after the body reads: every value `emit` returned (a name, or an
    /// expression of names).
    roots: std::collections::HashSet<String>,
    /// Where long bodies are split into functions.
    split: Split,
    names: HashMap<ExprId, String>,
    fetches: HashMap<String, String>,
    /// Textures this module reads: (name, binding).
    bindings: Vec<(String, View)>,
    /// Of those, the summed-area tables (storage buffers) and the unorm scale of their codes.
    tables: Vec<(String, u32)>,
    uses_params: bool,
    uses_sampler: bool,
    /// Map side: the resources the pass reads.
    reads: Vec<ResId>,
    counter: usize,
    /// Receiver side: the light samples whose views `at_sample` used, with the `in_*`
    /// locals of each view the body reads (the prologue computes only those).
    views: std::collections::BTreeMap<u8, std::collections::BTreeSet<&'static str>>,
    /// Map and geometry side, in a per-sample pass: per-sample resources are read at the
    /// layer block of the view being rendered (`frame.sample.x`).
    per_sample_pass: bool,
    /// Receiver side, in a deferred Shade's compute step: implicit-LOD lookups take their
    /// footprint from the G-buffer (`textureSampleGrad`), compute stages having no
    /// screen-space derivatives.
    deferred: bool,
}

impl<'a> Emitter<'a> {
    fn new(ir: &'a Program<'a>, site: Site, reads: Vec<ResId>) -> Self {
        Emitter {
            ir,
            site,
            body: Vec::new(),
            roots: Default::default(),
            split: Split::default(),
            names: HashMap::new(),
            fetches: HashMap::new(),
            bindings: vec![],
            tables: vec![],
            uses_params: false,
            uses_sampler: false,
            reads,
            counter: 0,
            views: Default::default(),
            per_sample_pass: false,
            deferred: false,
        }
    }

    /// The layer of `layer` of texture `t` of resource `res` in sample view `view`, as WGSL:
    /// a per-sample resource holds one block of `t.layers` layers per sample.
    fn view_layer(&self, res: ResId, t: usize, layer: u32, view: Option<u8>) -> String {
        let r = &self.ir.resources[res];
        let per = r.textures[t].layers;
        match view {
            Some(k) => format!("{}i", u32::from(k) * per + layer),
            None if self.per_sample_pass && self.ir.per_sample(res) => format!("(i32(frame.sample.x) * {per}i + {layer}i)"),
            None => format!("{layer}i"),
        }
    }

    fn binding(&mut self, texture: &str, view: View) -> String {
        if !self.bindings.iter().any(|(n, _)| n == texture) {
            self.bindings.push((texture.to_string(), view));
        }
        format!("t_{texture}")
    }

    fn fresh(&mut self, prefix: &str) -> String {
        self.counter += 1;
        format!("{prefix}{}", self.counter)
    }

    fn line(&mut self, s: &str) {
        self.body.push(Line::Raw(s.to_string()));
    }

    fn let_line(&mut self, name: &str, ty: &'static str, rhs: String) {
        self.body.push(Line::Let {
            name: name.to_string(),
            ty,
            rhs,
        });
    }

    /// The body's text and the functions it calls (long bodies are split: `back::parts`).
    /// `entry` names the entry point.
    fn finish(&self, entry: &str) -> (String, String) {
        parts::split(&self.body, entry, &self.roots, self.split)
    }

    fn input(&mut self, i: Input) -> String {
        // check refuses receiver inputs on the map side and geometry inputs outside
        // Geometry passes' channels
        debug_assert!(match self.site {
            Site::Receiver => i.side() != crate::builtins::Side::Geometry,
            Site::Geometry => matches!(i.side(), crate::builtins::Side::Both | crate::builtins::Side::Geometry),
            Site::Map => i.side() == crate::builtins::Side::Both,
        });
        i.desc().wgsl.to_string()
    }

    /// The WGSL texture name and decode of a channel in a resource: (binding, layer, component, encode).
    fn locate(&mut self, res: ResId, ch: ChannelId, view: View, sample: Option<u8>) -> Result<(String, String, u32, Encode), Diagnostic> {
        let r = &self.ir.resources[res];
        let slot = r
            .slot_of(ch)
            .ok_or_else(|| internal(format!("channel {} missing from `{}`", self.ir.channels[ch].name, r.name)))?;
        let (t, layer, comp) = slot.place();
        let name = r.textures[t].name.clone();
        let (comp, encode) = (comp, slot.encode);
        let layer = self.view_layer(res, t, layer, sample);
        let b = self.binding(&name, view);
        Ok((b, layer, comp, encode))
    }

    fn decode(stored: &str, e: Encode) -> String {
        if e.is_identity() {
            stored.to_string()
        } else {
            format!("({stored} * {} + {})", f32_lit((1.0 / e.scale) as f32), f32_lit(e.bias as f32))
        }
    }

    fn emit(&mut self, root: ExprId) -> Result<String, Diagnostic> {
        for h in self.ir.arena.postorder(&[root]) {
            if self.names.contains_key(&h) {
                continue;
            }
            let e = self.expr(h)?;
            let node = self.ir.arena.node(h);
            let leaf = matches!(
                node,
                Node::F32(_) | Node::I32(_) | Node::U32(_) | Node::Bool(_) | Node::Param(_) | Node::Input(..) | Node::Channel(..)
            );
            if leaf {
                self.names.insert(h, e);
            } else {
                let name = format!("e{}", h.index());
                self.let_line(&name, self.ir.arena.ty(h).wgsl(), e);
                self.names.insert(h, name);
            }
        }
        let name = self.names[&root].clone();
        self.roots.insert(name.clone());
        Ok(name)
    }

    fn n(&self, h: ExprId) -> &str {
        &self.names[&h]
    }

    fn expr(&mut self, h: ExprId) -> Result<String, Diagnostic> {
        let ir = self.ir;
        let a = &ir.arena;
        let node = a.node(h).clone();
        // Operations on constants that did not fold are invalid at compile time (x / 0, log(-1)).
        let ops = a.operands(h);
        let all_const = !ops.is_empty() && ops.iter().all(|o| a.as_const(*o).is_some());
        let exempt = matches!(node, Node::Sample { .. })
            || matches!(node, Node::Call(f, _) if matches!(f.desc().sig, Sig::Construct(_)))
            || (matches!(node, Node::Binary(BinOp::Div | BinOp::Rem, _, _)) && a.ty(h) == Ty::I32);
        if all_const && !exempt {
            return Err(
                Diagnostic::error(Phase::Codegen, format!("`{}` has no finite value", a.display(h, Some(ir))))
                    .at(a.span(h), "evaluates to infinity or NaN at compile time")
                    .help("check for a division by zero, the log or square root of a negative number, or an overflow"),
            );
        }
        Ok(match node {
            Node::F32(b) => f32_lit(f32::from_bits(b)),
            Node::I32(v) => i32_lit(v),
            Node::U32(v) => format!("{v}u"),
            Node::Bool(v) => v.to_string(),
            Node::Param(p) => {
                self.uses_params = true;
                let prm = &ir.params[p];
                if matches!(prm.value, ConstValue::Bool(_)) {
                    format!("(params.{} != 0u)", prm.name)
                } else {
                    format!("params.{}", prm.name)
                }
            }
            Node::Input(i, None) => self.input(i),
            Node::Input(i, Some(k)) => {
                let name = self.input(i);
                self.views.entry(k).or_default().insert(i.desc().wgsl);
                format!("{name}_v{k}")
            }
            Node::Channel(c, offset) => self.load_map_channel(c, offset)?,
            Node::Sample {
                channel,
                resource,
                how,
                args,
                view,
            } => self.sample(channel, resource, how, &args, view)?,
            Node::Unary(UnOp::Neg, x) => format!("-{}", self.n(x)),
            Node::Unary(UnOp::Not, x) => format!("!{}", self.n(x)),
            Node::Unary(UnOp::BitNot, x) => format!("~{}", self.n(x)),
            Node::Binary(op, x, y) => format!("{} {} {}", self.n(x), op.symbol(), self.n(y)),
            Node::Swizzle(x, c) => format!("{}.{}", self.n(x), c.iter().map(|i| COMP[*i as usize]).collect::<String>()),
            Node::Call(f, args) => {
                let v: Vec<String> = args.iter().map(|x| self.n(*x).to_string()).collect();
                f.wgsl_call(&v)
            }
        })
    }

    /// Map side: the value of a channel at this texel, read from the resource that carries it.
    fn load_map_channel(&mut self, c: ChannelId, [dx, dy]: [i32; 2]) -> Result<String, Diagnostic> {
        let res = self
            .reads
            .iter()
            .copied()
            .find(|&r| self.ir.resources[r].slot_of(c).is_some())
            .ok_or_else(|| internal("map channel not read"))?;
        let (tex, layer, comp, enc) = self.locate(res, c, View::Base, None)?;
        let key = format!("{tex}/{layer}/{dx},{dy}");
        let v = match self.fetches.get(&key) {
            Some(v) => v.clone(),
            None => {
                let v = self.fresh("texel_");
                // a neighbour: its texel, clamped to the map's edge
                let at = if (dx, dy) == (0, 0) {
                    "texel".to_string()
                } else {
                    format!(
                        "clamp(texel + vec2<i32>({}, {}), vec2<i32>(0i), vec2<i32>(textureDimensions({tex}).xy) - 1i)",
                        i32_lit(dx),
                        i32_lit(dy)
                    )
                };
                self.let_line(&v, "vec4<f32>", format!("textureLoad({tex}, {at}, {layer}, 0i)"));
                self.fetches.insert(key, v.clone());
                v
            }
        };
        Ok(Self::decode(&format!("{v}.{}", COMP[comp as usize]), enc))
    }

    fn sample(&mut self, ch: ChannelId, res: ResId, how: SampleFn, args: &[ExprId], view: Option<u8>) -> Result<String, Diagnostic> {
        if let Some(k) = view {
            self.views.entry(k).or_default();
        }
        let (tex, layer, comp, enc) = self.locate(res, ch, View::All, view)?;
        let args: Vec<String> = args.iter().map(|a| self.n(*a).to_string()).collect();
        let key = format!("{tex}/{layer}/{how:?}/{}", args.join(","));
        let v = match self.fetches.get(&key) {
            Some(v) => v.clone(),
            None => {
                let v = self.fresh("s");
                let call = match how.desc().wgsl {
                    SampleWgsl::SummedAreaTable => {
                        let r = &self.ir.resources[res];
                        let t = r.slot_of(ch).map(|s| &r.textures[s.texture]);
                        let scale = match t.map(|t| t.precision) {
                            Some(Precision::Unorm8) => 255,
                            Some(Precision::Unorm16) => 65535,
                            Some(Precision::F16 | Precision::F32) | None => {
                                return Err(internal("summed-area table over a non-unorm texture"));
                            }
                        };
                        let name = tex.trim_start_matches("t_").to_string();
                        if table_source(self.ir, res).is_none() {
                            return Err(internal("box lookup of a texture"));
                        }
                        if !self.tables.iter().any(|(n, _)| *n == name) {
                            self.tables.push((name.clone(), scale));
                        }
                        format!("box_{name}(in_uv, vec2<f32>({}, {}), {layer})", args[0], args[1])
                    }
                    // `shade_refusal` keeps per-sample implicit-LOD lookups forward
                    SampleWgsl::Texture { sampler, .. } if self.deferred && how == SampleFn::Sample && view.is_none() => {
                        self.uses_sampler |= sampler;
                        format!("textureSampleGrad({tex}, smp, in_uv, {layer}, in_duv_dx, in_duv_dy)")
                    }
                    SampleWgsl::Texture { sampler, read } => {
                        self.uses_sampler |= sampler;
                        read(&tex, &layer, &args)
                    }
                };
                // inside `at_sample(k, ..)`, the receiver's coordinates in view k
                let call = match view {
                    Some(k) => {
                        let used = self.views.entry(k).or_default();
                        for local in ["in_uv", "in_base"] {
                            if call.contains(local) {
                                used.insert(local);
                            }
                        }
                        in_view(&call, k)
                    }
                    None => call,
                };
                // every lookup returns the texel's four components
                self.let_line(&v, "vec4<f32>", call);
                self.fetches.insert(key, v.clone());
                v
            }
        };
        Ok(Self::decode(&format!("{v}.{}", COMP[comp as usize]), enc))
    }

    /// Module-level declarations for what the body used.
    fn declarations(&self, ir: &Program) -> String {
        let mut s = String::new();
        s.push_str(FRAME_WGSL);
        s.push_str("@group(0) @binding(0) var<uniform> frame: Frame;\n");
        if self.uses_params {
            s.push_str(&params_struct(ir));
            s.push_str("@group(0) @binding(1) var<uniform> params: Params;\n");
        }
        if self.uses_sampler {
            s.push_str("@group(0) @binding(2) var smp: sampler;\n");
        }
        if !self.views.is_empty() {
            s.push_str(graph::LIGHT_SAMPLES_WGSL);
            s.push_str("@group(0) @binding(3) var<uniform> light_samples: LightSamples;\n");
        }
        for (i, (name, _)) in self.bindings.iter().enumerate() {
            match self.tables.iter().find(|(n, _)| n == name) {
                Some((_, scale)) => {
                    let _ = writeln!(s, "@group(1) @binding({i}) var<storage, read> t_{name}: array<vec4<u32>>;");
                    s.push_str(&box_lookup(name, *scale));
                }
                None => {
                    let _ = writeln!(s, "@group(1) @binding({i}) var t_{name}: texture_2d_array<f32>;");
                }
            }
        }
        s
    }

    fn graph_bindings(&self) -> Vec<Binding> {
        self.bindings
            .iter()
            .enumerate()
            .map(|(i, (n, v))| Binding {
                binding: i as u32,
                texture: n.clone(),
                view: *v,
            })
            .collect()
    }
}

/// WGSL of a box lookup in summed-area table `t_{name}` (inclusive prefix sums of unorm
/// codes, u32, rows of `shadow_size.x` texels, layers one after another).
///
/// The box [lo, hi] (texel units) covers whole cells i0..i1 less the parts of the first and
/// last cell outside it, on each axis; the weights are separable, so the integral is nine
/// integer rectangles (whole block, two edge columns, two edge rows, four corners), each
/// summed exactly in wrapping u32 arithmetic (exact while a rectangle's sum stays below
/// 2^32: always for unorm8 up to 4096^2 texels, up to 65536 texels of area for unorm16)
/// before it is weighted in f32. A box one texel wide is bilinear interpolation.
fn box_lookup(name: &str, scale: u32) -> String {
    // p{y}{x}: the table at x in (i0.x - 1, i0.x, i1.x - 1, i1.x), y likewise: 16 loads
    let mut loads = String::new();
    for y in 0..4 {
        for x in 0..4 {
            let _ = writeln!(loads, "    let p{y}{x} = sat_{name}(xs[{x}], ys[{y}], layer);");
        }
    }
    // a rectangle of whole texels between table columns (xa, xb] and rows (ya, yb]
    let rect = |xa: u32, xb: u32, ya: u32, yb: u32| format!("vec4<f32>(p{yb}{xb} - p{yb}{xa} - p{ya}{xb} + p{ya}{xa})");
    format!(
        "
// inclusive prefix sum at texel (x, y); 0 left of or above the map
fn sat_{name}(x: i32, y: i32, layer: i32) -> vec4<u32> {{
    if x < 0i || y < 0i {{
        return vec4<u32>(0u);
    }}
    let n = vec2<i32>(frame.shadow_size.xy);
    return t_{name}[u32((layer * n.y + y) * n.x + x)];
}}

// mean stored value over a box `w` (uv units, at least one texel) centred at `uv`, clipped to the map
fn box_{name}(uv: vec2<f32>, w: vec2<f32>, layer: i32) -> vec4<f32> {{
    let n = frame.shadow_size.xy;
    let half = max(w * n, vec2<f32>(1.0)) * 0.5;
    let c = clamp(uv * n, vec2<f32>(0.0), n);
    let lo = clamp(c - half, vec2<f32>(0.0), n);
    let hi = clamp(c + half, vec2<f32>(0.0), n);
    let last = vec2<i32>(n) - 1i;
    let i0 = min(vec2<i32>(floor(lo)), last);
    let i1 = min(vec2<i32>(floor(hi)), last);
    // parts of the first and last cells outside the box
    let a = lo - vec2<f32>(i0);
    let b = vec2<f32>(i1) + 1.0 - hi;
    let xs = vec4<i32>(i0.x - 1i, i0.x, i1.x - 1i, i1.x);
    let ys = vec4<i32>(i0.y - 1i, i0.y, i1.y - 1i, i1.y);
{loads}    // whole block, less the outside parts of the edge columns and rows, plus the corners
    // they both removed; each rectangle summed exactly in u32 before weighting
    let total = {full}
        - a.x * {col0} - b.x * {col1}
        - a.y * {row0} - b.y * {row1}
        + a.x * a.y * {c00} + b.x * a.y * {c10}
        + a.x * b.y * {c01} + b.x * b.y * {c11};
    let area = (hi.x - lo.x) * (hi.y - lo.y);
    return total / (area * {scale}.0);
}}
",
        full = rect(0, 3, 0, 3),
        col0 = rect(0, 1, 0, 3),
        col1 = rect(2, 3, 0, 3),
        row0 = rect(0, 3, 0, 1),
        row1 = rect(0, 3, 2, 3),
        c00 = rect(0, 1, 0, 1),
        c10 = rect(2, 3, 0, 1),
        c01 = rect(0, 1, 2, 3),
        c11 = rect(2, 3, 2, 3),
    )
}

/// `wgsl` with the receiver's shadow-map coordinates (`in_uv`, `in_base`) replaced by
/// those of light sample `k`'s view.
fn in_view(wgsl: &str, k: u8) -> String {
    let mut out = String::with_capacity(wgsl.len() + 8);
    let mut rest = wgsl;
    while let Some(i) = rest.find("in_") {
        let (head, tail) = rest.split_at(i);
        out.push_str(head);
        let boundary = head.chars().last().is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
        let word = ["in_uv", "in_base"]
            .into_iter()
            .find(|w| tail.starts_with(w) && !tail[w.len()..].starts_with(|c: char| c.is_alphanumeric() || c == '_'));
        match word {
            Some(w) if boundary => {
                out.push_str(&format!("{w}_v{k}"));
                rest = &tail[w.len()..];
            }
            _ => {
                out.push_str("in_");
                rest = &tail[3..];
            }
        }
    }
    out.push_str(rest);
    out
}

/// The receiver seen from light sample `k`: the `in_*_v{k}` locals that `used` names (and
/// what they are computed from), as the centre's are computed from `frame`, from the
/// sample's view in `light_samples` (its own matrices, depth range and texel size; the
/// weights of its segments). Unused inputs are not emitted, so each sample costs only what
/// its lookups and inputs need.
fn sample_prologue(k: u8, used: &std::collections::BTreeSet<&'static str>) -> String {
    let uses = |names: &[&str]| names.iter().any(|n| used.contains(n));
    let slope = uses(&["in_depth_slope"]);
    let d = uses(&["in_d"]) || slope;
    let d_world = d || uses(&["in_d_world", "in_texel_depth"]);
    let texel_pos = uses(&["in_tf", "in_base"]);
    let uv = texel_pos || slope || uses(&["in_uv"]);
    let ndotl = uses(&["in_ndotl", "in_slope"]);
    let mut s = format!("    // the receiver seen from light sample {k}\n    let sv{k} = light_samples.views[{k}];\n");
    let mut line = |on: bool, text: String| {
        if on {
            s.push_str("    ");
            s.push_str(&text);
            s.push('\n');
        }
    };
    line(d_world, format!("let in_d_world_v{k} = -(sv{k}.view * world).z;"));
    line(
        d,
        format!("let in_d_v{k} = (in_d_world_v{k} - sv{k}.depth_range.x) * sv{k}.depth_range.z;"),
    );
    line(uv, format!("let light_clip_v{k} = sv{k}.view_proj * world;"));
    line(
        uv,
        format!("let in_uv_v{k} = light_clip_v{k}.xy / light_clip_v{k}.w * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5);"),
    );
    line(
        ndotl,
        format!("let in_ndotl_v{k} = dot(n, normalize(sv{k}.position.xyz - in.world));"),
    );
    line(
        uses(&["in_slope"]),
        format!("let in_slope_v{k} = min(sqrt(max(1.0 - in_ndotl_v{k} * in_ndotl_v{k}, 0.0)) / max(abs(in_ndotl_v{k}), 0.01), 100.0);"),
    );
    line(texel_pos, format!("let texel_pos_v{k} = in_uv_v{k} * frame.shadow_size.xy - 0.5;"));
    line(uses(&["in_tf"]), format!("let in_tf_v{k} = fract(texel_pos_v{k});"));
    line(
        uses(&["in_texel_depth"]),
        format!("let in_texel_depth_v{k} = sv{k}.weights.z * in_d_world_v{k} * sv{k}.depth_range.z;"),
    );
    line(uses(&["in_base"]), format!("let in_base_v{k} = vec2<i32>(floor(texel_pos_v{k}));"));
    if slope {
        for text in [
            format!("let duv_dx_v{k} = dpdx(in_uv_v{k});"),
            format!("let duv_dy_v{k} = dpdy(in_uv_v{k});"),
            format!("let dd_dx_v{k} = dpdx(in_d_v{k});"),
            format!("let dd_dy_v{k} = dpdy(in_d_v{k});"),
            format!("let det_v{k} = duv_dx_v{k}.x * duv_dy_v{k}.y - duv_dx_v{k}.y * duv_dy_v{k}.x;"),
            format!(
                "let g_v{k} = vec2<f32>(dd_dx_v{k} * duv_dy_v{k}.y - duv_dx_v{k}.y * dd_dy_v{k}, duv_dx_v{k}.x * dd_dy_v{k} - dd_dx_v{k} * duv_dy_v{k}.x);"
            ),
            format!(
                "let in_depth_slope_v{k} = select(0.0, min(length(g_v{k} / det_v{k}) * frame.shadow_size.z, 0.1), abs(det_v{k}) > 1e-14);"
            ),
        ] {
            line(true, text);
        }
    }
    line(
        uses(&["in_segment_before"]),
        format!("let in_segment_before_v{k} = sv{k}.weights.x;"),
    );
    line(uses(&["in_segment_after"]), format!("let in_segment_after_v{k} = sv{k}.weights.y;"));
    s
}

fn internal(msg: impl Into<String>) -> Diagnostic {
    Diagnostic::error(Phase::Codegen, format!("internal compiler error: {}", msg.into())).note("please report this with the technique file")
}

/// The `Params` uniform: every runtime param as one 4-byte field, in declaration order.
pub fn params_struct(ir: &Program) -> String {
    let mut s = String::from("struct Params {\n");
    for (_, p) in ir.uniform_params() {
        let ty = match p.value {
            ConstValue::Float(_) => "f32",
            ConstValue::Int(_) => "i32",
            ConstValue::Bool(_) | ConstValue::Uint(_) => "u32",
        };
        let _ = writeln!(s, "    {}: {ty},", p.name);
    }
    s.push_str("}\n");
    s
}

const FULLSCREEN_VS: &str = "@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(p * 2.0 - 1.0, 0.0, 1.0);
}
";

fn header(ir: &Program, pass: &IrPass) -> String {
    format!(
        "// Generated by sshc from technique `{}`: pass `{}` ({}). Do not edit.\n\n",
        ir.technique,
        pass.name,
        pass.kind_name()
    )
}

/// Groups of layers of one texture that one render pass writes together.
fn layer_chunks(t: &Texture, limits: &Limits) -> Vec<Vec<u32>> {
    let per = layers_per_subpass(t, limits);
    (0..t.layers).collect::<Vec<_>>().chunks(per as usize).map(|c| c.to_vec()).collect()
}

/// A full-screen step writing `layers` of `texture`.
fn fullscreen_step(entry: String, draw: Draw, reads: Vec<Binding>, texture: &str, layers: &[u32]) -> Step {
    Step {
        vertex: Some("vs_fullscreen".into()),
        fragment: Some(entry),
        compute: None,
        draw,
        reads,
        writes: layers
            .iter()
            .map(|&layer| Target {
                texture: texture.to_string(),
                layer,
            })
            .collect(),
        params: false,
        sampler: false,
        light_samples: false,
        cost: OpCount::default(),
    }
}

fn out_struct(name: &str, n: usize, depth: bool) -> String {
    let mut s = format!("struct {name} {{\n");
    for i in 0..n {
        let _ = writeln!(s, "    @location({i}) o{i}: vec4<f32>,");
    }
    if depth {
        s.push_str("    @builtin(frag_depth) depth: f32,\n");
    }
    s.push_str("}\n");
    s
}

pub fn codegen(ir: &Program, limits: &Limits, split: Split) -> Result<Output, Diagnostics> {
    let mut modules = Vec::new();
    let mut scratch = Vec::new();
    let mut diags = Diagnostics::default();
    for (pi, pass) in ir.passes.with_handles() {
        if !pass.live {
            continue;
        }
        let file = format!("{}.{}.wgsl", ir.technique, pass.name);
        let r = match &pass.kind {
            IrPassKind::Depth { .. } => depth(ir, pass),
            IrPassKind::Map => map(ir, pass, limits, split),
            IrPassKind::Filter { kernel } => filter(ir, pass, kernel, limits, &mut scratch),
            IrPassKind::Mipmap { reduce } => mipmap(ir, pass, *reduce, limits),
            IrPassKind::Shade { visibility } => shade(ir, pass, *visibility, split),
            IrPassKind::SummedArea => summed_area(ir, pass),
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

fn depth(ir: &Program, pass: &IrPass) -> Result<(String, Vec<Step>), Diagnostic> {
    let w = pass.writes.ok_or_else(|| internal("depth pass without output"))?;
    let res = &ir.resources[w];
    let slot = res.slots.first().ok_or_else(|| internal("depth resource without channel"))?;
    let (t, layer, comp) = slot.place();
    let tex = &res.textures[t];
    let mut s = header(ir, pass);
    s.push_str(FRAME_WGSL);
    s.push_str("@group(0) @binding(0) var<uniform> frame: Frame;\n\n");
    s.push_str(SCENE_FROM_LIGHT_VS);
    s.push_str(
        "
@fragment
fn fs_depth(in: DepthVarying) -> @location(0) vec4<f32> {
    // linear depth in [0, 1] between the fitted near and far planes (Annen 6.2.1 uses linear z)
    let z = (in.view_distance - frame.depth_range.x) * frame.depth_range.z;
",
    );
    let mut comps = ["0.0".to_string(), "0.0".into(), "0.0".into(), "1.0".into()];
    comps[comp as usize] = encode_expr("z", slot.encode);
    let _ = write!(s, "    return vec4<f32>({});\n}}\n", comps.join(", "));
    let step = Step {
        vertex: Some("vs_depth".into()),
        fragment: Some("fs_depth".into()),
        compute: None,
        draw: Draw::SceneFromLight,
        reads: vec![],
        writes: vec![Target {
            texture: tex.name.clone(),
            layer,
        }],
        params: false,
        sampler: false,
        light_samples: false,
        cost: OpCount::default(),
    };
    Ok((s, vec![step]))
}

fn encode_expr(v: &str, e: Encode) -> String {
    if e.is_identity() {
        v.to_string()
    } else {
        format!("({v} - {}) * {}", f32_lit(e.bias as f32), f32_lit(e.scale as f32))
    }
}

fn map(ir: &Program, pass: &IrPass, limits: &Limits, split: Split) -> Result<(String, Vec<Step>), Diagnostic> {
    let compute = map_runs_as_compute(ir, pass);
    let (signature, head) = if compute {
        (
            "@builtin(global_invocation_id) id: vec3<u32>",
            "    // invocations past the map's edge (the last workgroups) store nothing
    if any(vec2<f32>(id.xy) >= frame.shadow_size.xy) {
        return;
    }
    let texel = vec2<i32>(id.xy);\n",
        )
    } else {
        ("@builtin(position) pos: vec4<f32>", "    let texel = vec2<i32>(pos.xy);\n")
    };
    let entries = channel_entries(
        ir,
        pass,
        Site::Map,
        limits,
        EntryForm {
            signature,
            head,
            prelude: &|_| Ok(()),
            store: &|_, stored| Ok(stored),
            step: &|entry, texture, chunk| {
                let mut s = fullscreen_step(entry, Draw::FullScreen, vec![], texture, chunk);
                if compute {
                    (s.vertex, s.compute, s.draw) = (None, s.fragment.take(), Draw::ComputeTexels);
                }
                s
            },
            depth: None,
            split,
            compute,
        },
    )?;
    let src = format!(
        "{}{}\n{}\n{FULLSCREEN_VS}{}",
        header(ir, pass),
        entries.decl.declarations(ir),
        entries.structs,
        entries.bodies
    );
    Ok((src, entries.steps))
}

/// Warnings for textures a raster step writes in a format the limits profile cannot render
/// to (16-bit norm formats: an adapter-specific feature), naming the channels stored there
/// and the fix; the runtime refuses such a graph on a device without the feature.
pub fn render_target_warnings(ir: &Program, g: &graph::PassGraph, limits: &Limits) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    if limits.renderable_norm16 {
        return out;
    }
    let mut warned: Vec<&str> = Vec::new();
    for p in &g.passes {
        for st in p.steps.iter().filter(|s| !s.draw.is_dispatch()) {
            for w in &st.writes {
                if warned.contains(&w.texture.as_str()) {
                    continue;
                }
                let Some(d) = g.texture(&w.texture) else { continue };
                if !matches!(
                    d.format,
                    graph::Format::R16Unorm | graph::Format::Rg16Unorm | graph::Format::Rgba16Unorm
                ) {
                    continue;
                }
                warned.push(&w.texture);
                // the channels stored there (a filter's intermediate holds its source's)
                let stored: Vec<&IrChannel> = ir
                    .resources
                    .iter()
                    .flat_map(|r| {
                        r.textures
                            .iter()
                            .enumerate()
                            .filter(|(_, t)| t.name == d.name || format!("{}_tmp", t.name) == d.name)
                            .flat_map(move |(ti, _)| r.slots.iter().filter(move |s| s.texture == ti))
                    })
                    .map(|s| &ir.channels[s.channel])
                    .collect();
                let mut names: Vec<String> = Vec::new();
                for c in &stored {
                    let n = format!("`{}`", c.name);
                    if !names.contains(&n) {
                        names.push(n);
                    }
                }
                let mut diag = Diagnostic::warning(
                    Phase::Codegen,
                    format!(
                        "pass `{}` renders {} into {:?}, a 16-bit norm format that WebGPU renders to only with an adapter-specific feature",
                        p.name,
                        names.join(", "),
                        d.format
                    ),
                )
                .help("store them at F16 (or Unorm8, or F32); devices without the feature refuse the graph at load");
                match stored.first() {
                    Some(c) if c.precision_overridden => diag = diag.note("`--precision` set their precision"),
                    Some(c) => diag = diag.at(c.precision_span, "Unorm16 here"),
                    None => {}
                }
                out.push(diag);
            }
        }
    }
    out
}

/// Whether a Map, Filter or Mipmap pass runs as compute: its schedule asks for it and nothing
/// refuses it ([`compute_refusal`]).
pub fn map_runs_as_compute(ir: &Program, pass: &IrPass) -> bool {
    pass.schedule == Schedule::Compute && compute_refusal(ir, pass).is_none()
}

/// WebGPU's guaranteed workgroup memory (`maxComputeWorkgroupStorageSize`), bytes.
const WORKGROUP_MEMORY: u32 = 16384;

/// A Filter's workgroup tile in the compute schedule: (apron x, apron y, width, height) in
/// texels for a workgroup of [`graph::TEXEL_WORKGROUP`] squared invocations, on one axis
/// of a separable kernel (`horizontal`) or both (the 3 x 3 LoG).
fn filter_tile(kernel: &IrKernel, horizontal: bool) -> (i32, i32, i32, i32) {
    let r = (kernel.size() as i32 - 1) / 2;
    let (ax, ay) = match (kernel.separable(), horizontal) {
        (false, _) => (r, r),
        (true, true) => (r, 0),
        (true, false) => (0, r),
    };
    let g = graph::TEXEL_WORKGROUP as i32;
    (ax, ay, g + 2 * ax, g + 2 * ay)
}

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

/// How [`channel_entries`] writes one fragment entry.
struct EntryForm<'f, 'a> {
    /// The entry's parameters.
    signature: &'f str,
    /// Its first lines: `texel`, and the inputs as `in_*` locals.
    head: &'f str,
    /// Lines emitted through the entry's emitter before the values.
    prelude: &'f dyn Fn(&mut Emitter<'a>) -> Result<(), Diagnostic>,
    /// The stored expression of a component (given the slot and the encoded value).
    store: &'f dyn Fn(&PlacedSlot, String) -> Result<String, Diagnostic>,
    /// The step that runs an entry over some layers of a texture.
    step: &'f dyn Fn(String, &str, &[u32]) -> Step,
    /// The depth the entry writes (`@builtin(frag_depth)`), a WGSL expression.
    depth: Option<&'f str>,
    /// Where long bodies are split into functions.
    split: Split,
    /// Compute entries storing into storage textures (`Draw::ComputeTexels`) instead of
    /// fragment entries writing colour targets; `signature`, `head` and `step` fit them.
    compute: bool,
}

/// The fragment entries of a Map or Geometry pass: one per group of layers of each texture
/// of the resource it writes, computing its channels from their `value`s.
struct ChannelEntries<'a> {
    structs: String,
    bodies: String,
    /// In texture and layer order, with their reads and params.
    steps: Vec<Step>,
    /// Holds every binding and whether params are used, for the module's declarations.
    decl: Emitter<'a>,
}

fn channel_entries<'a>(
    ir: &'a Program,
    pass: &IrPass,
    site: Site,
    limits: &Limits,
    form: EntryForm<'_, 'a>,
) -> Result<ChannelEntries<'a>, Diagnostic> {
    let w = pass.writes.ok_or_else(|| internal("a pass computing channels without output"))?;
    let res = &ir.resources[w];
    let (mut bodies, mut structs, mut steps) = (String::new(), String::new(), Vec::new());
    // a per-sample pass reads per-sample resources in the view it renders
    let per_sample = matches!(
        pass.kind,
        IrPassKind::Geometry {
            view: LightView::PerSample,
            ..
        }
    );
    let mut decl = Emitter::new(ir, site, pass.reads.clone());
    decl.per_sample_pass = per_sample;
    for (ti, tex) in res.textures.iter().enumerate() {
        if form.compute {
            // group 2 binds the step's one written texture at binding 0
            let _ = writeln!(
                structs,
                "@group(2) @binding(0) var w_{}: texture_storage_2d_array<{}, write>;",
                tex.name,
                texture_format(tex).wgsl()
            );
        }
        for (ci, chunk) in layer_chunks(tex, limits).into_iter().enumerate() {
            let entry = format!("{}_{}_{ci}", if form.compute { "cs" } else { "fs" }, tex.name);
            let out_name = format!("Out_{}_{ci}", tex.name);
            if !form.compute {
                structs.push_str(&out_struct(&out_name, chunk.len(), form.depth.is_some()));
            }
            let mut em = Emitter::new(ir, site, pass.reads.clone());
            em.per_sample_pass = per_sample;
            em.split = form.split;
            em.bindings = decl.bindings.clone();
            (form.prelude)(&mut em)?;
            let mut outs = Vec::new();
            for (oi, &layer) in chunk.iter().enumerate() {
                let mut comps = vec!["0.0f".to_string(); 4];
                for slot in res.slots.iter().filter(|s| s.texture == ti && s.layer == layer) {
                    let v = ir.channels[slot.channel]
                        .value
                        .ok_or_else(|| internal(format!("channel `{}` without value", ir.channels[slot.channel].name)))?;
                    let name = em.emit(v)?;
                    comps[slot.component as usize] = (form.store)(slot, encode_expr(&name, slot.encode))?;
                }
                outs.push(if form.compute {
                    format!(
                        "    textureStore(w_{}, texel, {layer}i, vec4<f32>({}));",
                        tex.name,
                        comps.join(", ")
                    )
                } else {
                    format!("    out.o{oi} = vec4<f32>({});", comps.join(", "))
                });
            }
            if let Some(d) = form.depth {
                outs.push(format!("    out.depth = {d};"));
            }
            let (functions, body) = em.finish(&entry);
            bodies.push_str(&functions);
            if form.compute {
                let g = graph::TEXEL_WORKGROUP;
                let _ = write!(
                    bodies,
                    "\n@compute @workgroup_size({g}, {g})\nfn {entry}({}) {{\n{}{}{}\n}}\n",
                    form.signature,
                    form.head,
                    body,
                    outs.join("\n")
                );
            } else {
                let _ = write!(
                    bodies,
                    "\n@fragment\nfn {entry}({}) -> {out_name} {{\n{}{}    var out: {out_name};\n{}\n    return out;\n}}\n",
                    form.signature,
                    form.head,
                    body,
                    outs.join("\n")
                );
            }
            decl.bindings = em.bindings.clone();
            decl.uses_params |= em.uses_params;
            steps.push((form.step)(entry, &tex.name, &chunk));
        }
    }
    let bindings = decl.graph_bindings();
    for s in &mut steps {
        s.reads = bindings.clone();
        s.params = decl.uses_params;
    }
    Ok(ChannelEntries {
        structs,
        bodies,
        steps,
        decl,
    })
}

/// The buffer a Geometry pass's classification appends to.
fn geometry_buffer_name(pass: &IrPass) -> String {
    let skins = matches!(
        pass.kind,
        IrPassKind::Geometry {
            primitive: Primitive::Skins,
            ..
        }
    );
    format!("{}.{}", pass.name, if skins { "skins" } else { "silhouettes" })
}

/// The generated buffers of a module: one per `Silhouettes` step, laid out as its
/// primitive's library says.
fn geometry_buffers(pass: &IrPass, steps: &[Step]) -> Vec<graph::BufferDecl> {
    let IrPassKind::Geometry { primitive, .. } = pass.kind else {
        return vec![];
    };
    let Some(lib) = geometry::library(primitive) else {
        return vec![];
    };
    steps
        .iter()
        .filter(|s| s.draw.generates_records())
        .map(|_| graph::BufferDecl {
            name: geometry_buffer_name(pass),
            record_bytes: lib.record_bytes,
            vertices_per_record: lib.vertices_per_record,
        })
        .collect()
}

fn graph_resolve(r: Resolve) -> graph::Resolve {
    match r {
        Resolve::KeepMin => graph::Resolve::KeepMin,
        Resolve::KeepMax => graph::Resolve::KeepMax,
        Resolve::Add => graph::Resolve::Add,
        Resolve::Multiply => graph::Resolve::Multiply,
        Resolve::Nearest => graph::Resolve::Nearest,
    }
}

/// The scene drawn from the light, with each fragment's light-view distance: the vertex
/// stage of Depth passes and of `BackFaces`.
const SCENE_FROM_LIGHT_VS: &str = "struct DepthVarying {
    @builtin(position) clip: vec4<f32>,
    @location(0) view_distance: f32,
}

@vertex
fn vs_depth(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> DepthVarying {
    var out: DepthVarying;
    let world = vec4<f32>(position, 1.0);
    out.clip = frame.light_view_proj * world;
    out.view_distance = -(frame.light_view * world).z;
    return out;
}
";

/// A Geometry pass: one fragment entry per group of layers, writing the pass's channels
/// per fragment of its primitives; overlaps combine by the resolve rule (graph
/// `Resolve`): blending, or a depth test (`Nearest`). `Add` keeps `1 - sum(1 - v)`: its
/// fragments write the shadow amount `1 - v`. Primitives built from silhouettes come
/// from their library (classification on the GPU, primitives pulled from its records;
/// `back/geometry.rs`); `BackFaces` draws the scene's triangles that face away from the
/// light (Lawlor 2006, section 3.1, step 3). Fragments failing `keep` are discarded.
fn geometry(
    ir: &Program,
    pass: &IrPass,
    primitive: Primitive,
    resolve: Resolve,
    keep: Option<ExprId>,
    limits: &Limits,
    split: Split,
) -> Result<(String, Vec<Step>), Diagnostic> {
    let w = pass.writes.ok_or_else(|| internal("geometry pass without output"))?;
    let res = &ir.resources[w];
    for tex in &res.textures {
        if tex.precision == Precision::F32 && resolve != Resolve::Nearest {
            let ch = res
                .slots
                .iter()
                .find(|s| res.textures[s.texture].name == tex.name)
                .map(|s| ir.channels[s.channel].name.clone())
                .unwrap_or_default();
            return Err(Diagnostic::error(
                Phase::Codegen,
                format!(
                    "pass `{}` blends channel `{ch}` at F32: WebGPU blends 32-bit float targets only with an optional feature",
                    pass.name
                ),
            )
            .at(pass.span, "overlapping primitives are resolved by blending")
            .help("declare the channel F16, Unorm8 or Unorm16"));
        }
    }
    let lib = geometry::library(primitive);
    // The foremost surface the light sees: the channel of the Depth resource the pass
    // reads. The penumbra map holds the penumbrae of those surfaces only (Wyman & Hansen
    // 2003, section 3), so fragments behind it are discarded (the paper's fragment
    // program, line 4).
    let surface = if primitive.behind_the_lit_surface_discarded() {
        Some(
            pass.reads
                .iter()
                .find(|&&r| matches!(ir.passes[ir.resources[r].writer].kind, IrPassKind::Depth { .. }))
                .and_then(|&r| ir.resources[r].slots.first().map(|s| s.channel))
                .ok_or_else(|| {
                    Diagnostic::error(Phase::Codegen, format!("Geometry pass `{}` reads no Depth resource", pass.name))
                        .at(pass.span, "cones and sheets need the surface the light sees at each texel")
                        .help("add the Depth pass's resource to `reads`")
                })?,
        )
    } else {
        None
    };
    // Skins: the per-sample Depth resource whose discontinuities they span, and the
    // detector's threshold.
    let skins = if primitive.joins_sample_views() {
        let depth = pass
            .reads
            .iter()
            .copied()
            .find(|&r| matches!(ir.passes[ir.resources[r].writer].kind, IrPassKind::Depth { .. }))
            .ok_or_else(|| internal("Skins pass without a Depth resource (check refuses it)"))?;
        let threshold = ir
            .params
            .iter()
            .find(|p| p.name == geometry::SKIN_THRESHOLD_PARAM)
            .ok_or_else(|| {
                Diagnostic::error(
                    Phase::Codegen,
                    format!("Skins pass `{}` needs the param `{}`", pass.name, geometry::SKIN_THRESHOLD_PARAM),
                )
                .at(pass.span, "its discontinuity detector has no threshold")
                .note("a skin spans a depth step larger than the threshold (normalised depth) where the map's 3x3 Laplacian of Gaussian exceeds it too")
                .help(format!(
                    "declare `{}: (type: F32, default: 0.02)` in `params`",
                    geometry::SKIN_THRESHOLD_PARAM
                ))
            })?;
        let IrPassKind::Geometry { from: Some(from), .. } = pass.kind else {
            return Err(internal("Skins pass without `from` (check refuses it)"));
        };
        Some((depth, threshold, from))
    } else {
        None
    };
    let buffer = geometry_buffer_name(pass);
    let (signature, head) = match &lib {
        Some(lib) => (
            format!("in: {}", lib.varying),
            format!("    let texel = vec2<i32>(in.clip.xy);\n{}", lib.inputs),
        ),
        None => (
            "in: DepthVarying, @builtin(front_facing) front: bool".to_string(),
            "    let texel = vec2<i32>(in.clip.xy);\n    let in_z_frag = in.view_distance;\n".to_string(),
        ),
    };
    let entries = channel_entries(
        ir,
        pass,
        Site::Geometry,
        limits,
        EntryForm {
            signature: &signature,
            head: &head,
            prelude: &|em| {
                if let Some(surface) = surface {
                    let z = em.load_map_channel(surface, [0, 0])?;
                    em.line(&format!(
                        "let in_z_surface = frame.depth_range.x + {z} * (frame.depth_range.y - frame.depth_range.x);"
                    ));
                    em.line("if in_z_frag > in_z_surface {\n        discard;\n    }");
                }
                if lib.is_none() {
                    // winding seen from the light: counter-clockwise faces it
                    em.line("if front {\n        discard;\n    }");
                }
                if let Some(k) = keep {
                    let k = em.emit(k)?;
                    em.line(&format!("if !({k}) {{\n        discard;\n    }}"));
                }
                Ok(())
            },
            store: &|slot, stored| {
                if !slot.encode.is_identity() && matches!(resolve, Resolve::Add | Resolve::Multiply) {
                    return Err(Diagnostic::error(
                        Phase::Codegen,
                        format!(
                            "pass `{}` adds or multiplies channel `{}`, whose storage is scaled to its range",
                            pass.name, ir.channels[slot.channel].name
                        ),
                    )
                    .at(pass.span, "sums and products of scaled values are not the scaled sum or product")
                    .help("give the channel a range inside [0, 1], or resolve with KeepMin or KeepMax"));
                }
                Ok(match resolve {
                    Resolve::Add => format!("1.0 - {stored}"),
                    Resolve::KeepMin | Resolve::KeepMax | Resolve::Multiply | Resolve::Nearest => stored,
                })
            },
            step: &|entry, texture, chunk| match &lib {
                Some(lib) => {
                    let mut step = fullscreen_step(
                        entry,
                        Draw::Primitives {
                            buffer: buffer.clone(),
                            resolve: graph_resolve(resolve),
                        },
                        vec![],
                        texture,
                        chunk,
                    );
                    step.vertex = Some(lib.vertex.into());
                    step
                }
                None => {
                    let mut step = fullscreen_step(entry, Draw::SceneFromLight, vec![], texture, chunk);
                    step.vertex = Some("vs_depth".into());
                    step
                }
            },
            depth: lib.as_ref().and_then(|l| l.depth),
            split,
            compute: false,
        },
    )?;
    let mut entries = entries;
    let mut steps = Vec::new();
    let mut prefix = String::new();
    if let Some((depth, threshold, from)) = skins {
        // the source map's depth, decoded, and the threshold, ahead of the library
        let r = &ir.resources[depth];
        let slot = r.slots.first().ok_or_else(|| internal("depth resource without channel"))?;
        let (t, layer, comp) = slot.place();
        let per = r.textures[t].layers;
        let tex = entries.decl.binding(&r.textures[t].name, View::Base);
        let stored = format!(
            "textureLoad({tex}, clamp(t, vec2<i32>(0i), vec2<i32>(frame.shadow_size.xy) - 1i), view * {per}i + {layer}i, 0i).{}",
            COMP[comp as usize]
        );
        let tau = if threshold.uniform {
            entries.decl.uses_params = true;
            format!("params.{}", threshold.name)
        } else {
            f32_lit(threshold.value.as_f64() as f32)
        };
        let _ = write!(
            prefix,
            "{}@group(0) @binding(3) var<uniform> light_samples: LightSamples;

const SKIN_FROM: i32 = {};

// linear depth of sample view `view` at texel t (clamped to the map)
fn sk_depth(t: vec2<i32>, view: i32) -> f32 {{
    return {};
}}

// the discontinuity threshold, normalised depth (param `{}`)
fn sk_threshold() -> f32 {{
    return {tau};
}}
",
            graph::LIGHT_SAMPLES_WGSL,
            match from {
                graph::Neighbour::Previous => "-1i",
                graph::Neighbour::Next => "1i",
            },
            Emitter::decode(&stored, slot.encode),
            threshold.name
        );
        let bindings = entries.decl.graph_bindings();
        for s in &mut entries.steps {
            s.reads = bindings.clone();
            s.params = entries.decl.uses_params;
        }
        steps.push(Step {
            vertex: None,
            fragment: None,
            compute: Some("cs_skins".into()),
            draw: Draw::Discontinuities {
                buffer: buffer.clone(),
                source: from,
            },
            reads: bindings,
            writes: vec![],
            params: entries.decl.uses_params,
            sampler: false,
            light_samples: true,
            cost: OpCount::default(),
        });
    } else if let Some(lib) = &lib {
        steps.push(Step {
            vertex: None,
            fragment: None,
            compute: Some(lib.compute.into()),
            draw: Draw::Silhouettes { buffer: buffer.clone() },
            reads: vec![],
            writes: vec![],
            params: false,
            sampler: false,
            light_samples: false,
            cost: OpCount::default(),
        });
    }
    steps.extend(entries.steps);
    let library = match &lib {
        Some(lib) => format!("{prefix}{}", lib.source),
        None => SCENE_FROM_LIGHT_VS.to_string(),
    };
    let src = format!(
        "{}{}\n{}\n{}{}",
        header(ir, pass),
        entries.decl.declarations(ir),
        library,
        entries.structs,
        entries.bodies
    );
    Ok((src, steps))
}

/// Weights and combine rule of one axis of a separable kernel, or the 3x3 stencil.
fn filter(
    ir: &Program,
    pass: &IrPass,
    kernel: &IrKernel,
    limits: &Limits,
    scratch: &mut Vec<Scratch>,
) -> Result<(String, Vec<Step>), Diagnostic> {
    let src = &ir.resources[pass.reads[0]];
    let dst = &ir.resources[pass.writes.ok_or_else(|| internal("filter without output"))?];
    let mut s = header(ir, pass);
    s.push_str(FRAME_WGSL);
    s.push_str("@group(0) @binding(0) var<uniform> frame: Frame;\n");
    s.push_str("@group(1) @binding(0) var t_src: texture_2d_array<f32>;\n\n");
    s.push_str(FULLSCREEN_VS);
    let mut steps = Vec::new();
    let size = kernel.size() as i32;
    let r = (size - 1) / 2;
    // out = ((f / scale_in + bias_in * W) - bias_out) * scale_out, W = sum of weights
    let sum_w = if matches!(kernel, IrKernel::LoG) { 0.0 } else { 1.0 };
    let compute = map_runs_as_compute(ir, pass);
    for (ti, tex) in dst.textures.iter().enumerate() {
        let src_tex = &src.textures[ti];
        let tmp_tex = Texture {
            name: format!("{}_tmp", tex.name),
            precision: scratch_precision(tex.precision),
            ..tex.clone()
        };
        let passes: Vec<(&str, bool)> = if kernel.separable() {
            vec![("h", true), ("v", false)]
        } else {
            vec![("2d", false)]
        };
        let tmp = tmp_tex.name.clone();
        if kernel.separable() {
            scratch.push(Scratch {
                name: tmp.clone(),
                like: tex.name.clone(),
                format: texture_format(&tmp_tex),
            });
        }
        for (axis, horizontal) in passes {
            // each axis writes as many layers at once as its target's format allows
            let written = if kernel.separable() && horizontal { &tmp_tex } else { tex };
            let (ax, ay, tw, th) = filter_tile(kernel, horizontal);
            if compute {
                let _ = writeln!(
                    s,
                    "@group(2) @binding(0) var w_{}: texture_storage_2d_array<{}, write>;",
                    written.name,
                    texture_format(written).wgsl()
                );
            }
            for (ci, chunk) in layer_chunks(written, limits).iter().enumerate() {
                let entry = format!("{}_{}_{axis}_{ci}", if compute { "cs" } else { "fs" }, tex.name);
                let out_name = format!("Out_{}_{axis}_{ci}", tex.name);
                let tile = format!("tile_{}_{axis}_{ci}", tex.name);
                if compute {
                    let g = graph::TEXEL_WORKGROUP;
                    let _ = write!(
                        s,
                        "\n// the workgroup's {g} x {g} texels and the kernel's apron, one layer at a time
var<workgroup> {tile}: array<vec4<f32>, {}>;

@compute @workgroup_size({g}, {g})
fn {entry}(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {{
    let texel = vec2<i32>(id.xy);
    let last = vec2<i32>(textureDimensions(t_src)) - 1i;
    // no early return: every invocation takes part in the loads and barriers
    let inside = all(vec2<f32>(id.xy) < frame.shadow_size.xy);
    let origin = vec2<i32>(wg.xy) * {g}i - vec2<i32>({ax}i, {ay}i);
    let local = vec2<i32>(i32(li % {g}u), i32(li / {g}u));
",
                        tw * th
                    );
                } else {
                    s.push_str(&out_struct(&out_name, chunk.len(), false));
                    let _ = write!(
                        s,
                        "\n@fragment\nfn {entry}(@builtin(position) pos: vec4<f32>) -> {out_name} {{\n    let texel = vec2<i32>(pos.xy);\n    let last = vec2<i32>(textureDimensions(t_src)) - 1i;\n    var out: {out_name};\n"
                    );
                }
                for (oi, &layer) in chunk.iter().enumerate() {
                    let taps: Vec<(i32, i32, f64)> = match kernel {
                        IrKernel::LoG => (0..9)
                            .filter(|i| IrKernel::LOG_3X3[*i] != 0.0)
                            .map(|i| (i as i32 % 3 - 1, i as i32 / 3 - 1, IrKernel::LOG_3X3[i]))
                            .collect(),
                        IrKernel::Box(_) | IrKernel::Gaussian(..) | IrKernel::Max(_) | IrKernel::Min(_) => {
                            let w = kernel.weights_1d().unwrap_or_else(|| vec![1.0; size as usize]);
                            (-r..=r)
                                .map(|i| {
                                    if horizontal {
                                        (i, 0, w[(i + r) as usize])
                                    } else {
                                        (0, i, w[(i + r) as usize])
                                    }
                                })
                                .collect()
                        }
                    };
                    let _ = writeln!(s, "    // layer {layer}");
                    if compute {
                        // each invocation loads every 64th texel of the tile: one global
                        // load per texel and layer instead of one per tap
                        let n = tw * th;
                        let g2 = (graph::TEXEL_WORKGROUP * graph::TEXEL_WORKGROUP) as i32;
                        for j in 0..(n + g2 - 1) / g2 {
                            let _ = writeln!(s, "    let k{oi}_{j} = i32(li) + {}i;", j * g2);
                            let load = format!(
                                "{tile}[k{oi}_{j}] = textureLoad(t_src, clamp(origin + vec2<i32>(k{oi}_{j} % {tw}i, k{oi}_{j} / {tw}i), vec2<i32>(0i), last), {layer}i, 0i);"
                            );
                            if (j + 1) * g2 > n {
                                let _ = writeln!(s, "    if k{oi}_{j} < {n}i {{\n        {load}\n    }}");
                            } else {
                                let _ = writeln!(s, "    {load}");
                            }
                        }
                        s.push_str("    workgroupBarrier();\n");
                        for (k, (dx, dy, _)) in taps.iter().enumerate() {
                            let _ = writeln!(
                                s,
                                "    let a{oi}_{k} = {tile}[(local.y + {}i) * {tw}i + local.x + {}i];",
                                ay + dy,
                                ax + dx
                            );
                        }
                        // the next layer's loads overwrite the tile
                        s.push_str("    workgroupBarrier();\n");
                    } else {
                        for (k, (dx, dy, _)) in taps.iter().enumerate() {
                            let _ = writeln!(
                                s,
                                "    let a{oi}_{k} = textureLoad(t_src, clamp(texel + vec2<i32>({dx}i, {dy}i), vec2<i32>(0i), last), {layer}i, 0i);"
                            );
                        }
                    }
                    let combined = match kernel {
                        IrKernel::Max(_) => taps
                            .iter()
                            .enumerate()
                            .map(|(k, _)| format!("a{oi}_{k}"))
                            .reduce(|a, b| format!("max({a}, {b})"))
                            .unwrap_or_default(),
                        IrKernel::Min(_) => taps
                            .iter()
                            .enumerate()
                            .map(|(k, _)| format!("a{oi}_{k}"))
                            .reduce(|a, b| format!("min({a}, {b})"))
                            .unwrap_or_default(),
                        IrKernel::Box(_) | IrKernel::Gaussian(..) | IrKernel::LoG => taps
                            .iter()
                            .enumerate()
                            .map(|(k, (_, _, w))| format!("a{oi}_{k} * {}", f32_lit(*w as f32)))
                            .collect::<Vec<_>>()
                            .join(" + "),
                    };
                    // Encodes differ only across a LoG (its output range is wider).
                    let last_axis = !kernel.separable() || !horizontal;
                    let mut value = combined;
                    if last_axis {
                        let mut fix = Vec::new();
                        let mut any = false;
                        for c in 0..4u32 {
                            let enc_in = src.slots.iter().find(|sl| sl.place() == (ti, layer, c)).map(|sl| sl.encode);
                            let enc_out = dst.slots.iter().find(|sl| sl.place() == (ti, layer, c)).map(|sl| sl.encode);
                            match (enc_in, enc_out) {
                                (Some(i), Some(o)) if i != o || sum_w != 1.0 => {
                                    any = true;
                                    fix.push((1.0 / i.scale * o.scale, (i.bias * sum_w - o.bias) * o.scale));
                                }
                                _ => fix.push((1.0, 0.0)),
                            }
                        }
                        if any {
                            let m: Vec<String> = fix.iter().map(|f| f32_lit(f.0 as f32)).collect();
                            let b: Vec<String> = fix.iter().map(|f| f32_lit(f.1 as f32)).collect();
                            value = format!("({value}) * vec4<f32>({}) + vec4<f32>({})", m.join(", "), b.join(", "));
                        }
                    }
                    if compute {
                        let _ = writeln!(
                            s,
                            "    if inside {{\n        textureStore(w_{}, texel, {layer}i, {value});\n    }}",
                            written.name
                        );
                    } else {
                        let _ = writeln!(s, "    out.o{oi} = {value};");
                    }
                }
                s.push_str(if compute { "}\n" } else { "    return out;\n}\n" });
                let (read, write) = match (kernel.separable(), horizontal) {
                    (true, true) => (src_tex.name.clone(), tmp.clone()),
                    (true, false) => (tmp.clone(), tex.name.clone()),
                    _ => (src_tex.name.clone(), tex.name.clone()),
                };
                let mut step = fullscreen_step(
                    entry,
                    Draw::FullScreen,
                    vec![Binding {
                        binding: 0,
                        texture: read,
                        view: View::Base,
                    }],
                    &write,
                    chunk,
                );
                if compute {
                    (step.vertex, step.compute, step.draw) = (None, step.fragment.take(), Draw::ComputeTexels);
                }
                steps.push(step);
            }
        }
    }
    Ok((s, steps))
}

/// A summed-area table in two compute steps: running sums along each row of the unorm
/// codes (`round(v * scale)`, exact integers), then along each column in place. u32
/// addition wraps; box sums taken from the table are exact while they stay below 2^32.
fn summed_area(ir: &Program, pass: &IrPass) -> Result<(String, Vec<Step>), Diagnostic> {
    let src = &ir.resources[pass.reads[0]];
    let dst = &ir.resources[pass.writes.ok_or_else(|| internal("summed-area pass without output"))?];
    let mut s = header(ir, pass);
    s.push_str(FRAME_WGSL);
    s.push_str("@group(0) @binding(0) var<uniform> frame: Frame;\n");
    for (i, t) in src.textures.iter().enumerate() {
        let _ = writeln!(s, "@group(1) @binding({i}) var t_{}: texture_2d_array<f32>;", t.name);
    }
    for (i, t) in dst.textures.iter().enumerate() {
        let _ = writeln!(
            s,
            "@group(2) @binding({i}) var<storage, read_write> sat_{}: array<vec4<u32>>;",
            t.name
        );
    }
    let mut rows = String::new();
    let mut cols = String::new();
    for (st, dt) in src.textures.iter().zip(&dst.textures) {
        let scale = match st.precision {
            Precision::Unorm8 => 255,
            Precision::Unorm16 => 65535,
            Precision::F16 | Precision::F32 => return Err(internal("summed-area table over a non-unorm texture")),
        };
        let _ = write!(
            rows,
            "    for (var layer = 0u; layer < {layers}u; layer++) {{
        var acc = vec4<u32>(0u);
        let row = (layer * n.y + y) * n.x;
        for (var x = 0u; x < n.x; x++) {{
            acc += vec4<u32>(round(textureLoad(t_{src}, vec2<u32>(x, y), layer, 0i) * {scale}.0));
            sat_{dst}[row + x] = acc;
        }}
    }}
",
            layers = st.layers,
            src = st.name,
            dst = dt.name
        );
        let _ = write!(
            cols,
            "    for (var layer = 0u; layer < {layers}u; layer++) {{
        var acc = vec4<u32>(0u);
        for (var y = 0u; y < n.y; y++) {{
            let i = (layer * n.y + y) * n.x + x;
            acc += sat_{dst}[i];
            sat_{dst}[i] = acc;
        }}
    }}
",
            layers = dt.layers,
            dst = dt.name
        );
    }
    let wg = sshc_graph::COMPUTE_WORKGROUP;
    let _ = write!(
        s,
        "
// one invocation per row: running sums of the unorm codes along the row
@compute @workgroup_size({wg})
fn cs_rows(@builtin(global_invocation_id) id: vec3<u32>) {{
    let n = vec2<u32>(frame.shadow_size.xy);
    let y = id.x;
    if y >= n.y {{
        return;
    }}
{rows}}}

// one invocation per column: running sums down the column, in place
@compute @workgroup_size({wg})
fn cs_columns(@builtin(global_invocation_id) id: vec3<u32>) {{
    let n = vec2<u32>(frame.shadow_size.xy);
    let x = id.x;
    if x >= n.x {{
        return;
    }}
{cols}}}
"
    );
    let writes: Vec<Target> = dst
        .textures
        .iter()
        .map(|t| Target {
            texture: t.name.clone(),
            layer: 0,
        })
        .collect();
    let compute_step = |entry: &str, draw: Draw, reads: Vec<Binding>| Step {
        vertex: None,
        fragment: None,
        compute: Some(entry.to_string()),
        draw,
        reads,
        writes: writes.clone(),
        params: false,
        sampler: false,
        light_samples: false,
        cost: OpCount::default(),
    };
    let reads = src
        .textures
        .iter()
        .enumerate()
        .map(|(i, t)| Binding {
            binding: i as u32,
            texture: t.name.clone(),
            view: View::Base,
        })
        .collect();
    Ok((
        s,
        vec![
            compute_step("cs_rows", Draw::ComputeRows, reads),
            compute_step("cs_columns", Draw::ComputeColumns, vec![]),
        ],
    ))
}

fn mipmap(ir: &Program, pass: &IrPass, reduce: Reduce, limits: &Limits) -> Result<(String, Vec<Step>), Diagnostic> {
    let dst = &ir.resources[pass.writes.ok_or_else(|| internal("mipmap without output"))?];
    let compute = map_runs_as_compute(ir, pass);
    let mut s = header(ir, pass);
    s.push_str(FRAME_WGSL);
    s.push_str("@group(0) @binding(0) var<uniform> frame: Frame;\n");
    s.push_str("// the level above the one being written\n@group(1) @binding(0) var t_src: texture_2d_array<f32>;\n\n");
    s.push_str(FULLSCREEN_VS);
    let mut steps = Vec::new();
    for tex in &dst.textures {
        if compute {
            let _ = writeln!(
                s,
                "// the level being written\n@group(2) @binding(0) var w_{}: texture_storage_2d_array<{}, write>;",
                tex.name,
                texture_format(tex).wgsl()
            );
        }
        for (ci, chunk) in layer_chunks(tex, limits).into_iter().enumerate() {
            let entry = format!("{}_{}_{ci}", if compute { "cs" } else { "fs" }, tex.name);
            let out_name = format!("Out_{}_{ci}", tex.name);
            if compute {
                let g = graph::TEXEL_WORKGROUP;
                let _ = write!(
                    s,
                    "\n@compute @workgroup_size({g}, {g})\nfn {entry}(@builtin(global_invocation_id) id: vec3<u32>) {{\n    // invocations past the level's edge store nothing\n    if any(id.xy >= textureDimensions(w_{})) {{\n        return;\n    }}\n    let texel = vec2<i32>(id.xy);\n    let src = texel * 2i;\n    let last = vec2<i32>(textureDimensions(t_src)) - 1i;\n",
                    tex.name
                );
            } else {
                s.push_str(&out_struct(&out_name, chunk.len(), false));
                let _ = write!(
                    s,
                    "\n@fragment\nfn {entry}(@builtin(position) pos: vec4<f32>) -> {out_name} {{\n    let src = vec2<i32>(pos.xy) * 2i;\n    let last = vec2<i32>(textureDimensions(t_src)) - 1i;\n    var out: {out_name};\n"
                );
            }
            for (oi, &layer) in chunk.iter().enumerate() {
                for (k, (dx, dy)) in [(0, 0), (1, 0), (0, 1), (1, 1)].iter().enumerate() {
                    let _ = writeln!(
                        s,
                        "    let a{oi}_{k} = textureLoad(t_src, min(src + vec2<i32>({dx}i, {dy}i), last), {layer}i, 0i);"
                    );
                }
                let v = match reduce {
                    Reduce::Mean => format!("(a{oi}_0 + a{oi}_1 + a{oi}_2 + a{oi}_3) * 0.25"),
                    Reduce::Max => format!("max(max(a{oi}_0, a{oi}_1), max(a{oi}_2, a{oi}_3))"),
                    Reduce::Min => format!("min(min(a{oi}_0, a{oi}_1), min(a{oi}_2, a{oi}_3))"),
                };
                if compute {
                    let _ = writeln!(s, "    textureStore(w_{}, texel, {layer}i, {v});", tex.name);
                } else {
                    let _ = writeln!(s, "    out.o{oi} = {v};");
                }
            }
            s.push_str(if compute { "}\n" } else { "    return out;\n}\n" });
            let mut step = fullscreen_step(
                entry,
                Draw::MipLevels,
                vec![Binding {
                    binding: 0,
                    texture: tex.name.clone(),
                    view: View::PreviousLevel,
                }],
                &tex.name,
                &chunk,
            );
            if compute {
                (step.vertex, step.compute, step.draw) = (None, step.fragment.take(), Draw::ComputeMipLevels);
            }
            steps.push(step);
        }
    }
    Ok((s, steps))
}

/// What the camera raster of both Shade schedules interpolates.
// The clip position is `@invariant`: the runtime redraws the objects that receive no
// shadow with its own vertex stage of the same expression, testing depth Equal against this
// raster's (runtime/src/receivers.rs), which invariance makes exact.
const SHADE_VARYING: &str = "
struct ShadeVarying {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
}
";

/// The camera raster's vertex stage: the scene's world position and normal.
const SHADE_VERTEX: &str = "
@vertex
fn vs_shade(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> ShadeVarying {
    var out: ShadeVarying;
    out.clip = frame.camera_view_proj * vec4<f32>(position, 1.0);
    out.world = position;
    out.normal = normal;
    return out;
}
";

/// The receiver's normal, in a fragment entry taking `in: ShadeVarying`.
const SHADE_NORMAL: &str = graph::SHADE_NORMAL_WGSL;

/// The receiver seen from the light's centre, from `in.world`, `world` and `n`; `distant`,
/// where the graph is specialised for a scene, keeps only the form of the
/// direction to the light and of the texel's size that the light's kind takes.
fn shade_receiver(distant: Option<bool>) -> String {
    let to_light = match distant {
        None => {
            "select(normalize(frame.light_position.xyz - in.world), normalize(frame.light_position.xyz), frame.light_position.w == 0.0)"
        }
        Some(false) => "normalize(frame.light_position.xyz - in.world)",
        Some(true) => "normalize(frame.light_position.xyz)",
    };
    let texel = match distant {
        None => "frame.texel_world.x * in_d_world + frame.texel_world.y",
        // perspective: y is 0; orthographic: x is 0 (sshc_graph's `texel_world`)
        Some(false) => "frame.texel_world.x * in_d_world",
        Some(true) => "frame.texel_world.y",
    };
    format!(
        "    let in_d_world = -(frame.light_view * world).z;
    let in_d = (in_d_world - frame.depth_range.x) * frame.depth_range.z;
    let light_clip = frame.light_view_proj * world;
    let in_uv = light_clip.xy / light_clip.w * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5);
    let to_light = {to_light};
    let in_ndotl = dot(n, to_light);
    // tan(acos(ndotl)), for slope-scaled bias
    let in_slope = min(sqrt(max(1.0 - in_ndotl * in_ndotl, 0.0)) / max(abs(in_ndotl), 0.01), 100.0);
    let texel_pos = in_uv * frame.shadow_size.xy - 0.5;
    let in_tf = fract(texel_pos);
    // one shadow-map texel at the receiver, in normalised depth units
    let in_texel_depth = ({texel}) * frame.depth_range.z;
    let in_base = vec2<i32>(floor(texel_pos));
"
    )
}

/// The receiver-plane depth slope's derivatives, in a fragment entry (screen-space
/// derivatives); `DEPTH_SLOPE` (the schema's, shared with the runtime's host pixels)
/// follows it.
const SHADE_SLOPE: &str = "    // receiver-plane depth gradient over uv from screen-space derivatives (Isidoro 2006):
    // solve [duv/dx; duv/dy] g = [dd/dx; dd/dy]; 0 where the Jacobian is singular
    let duv_dx = dpdx(in_uv);
    let duv_dy = dpdy(in_uv);
    let dd_dx = dpdx(in_d);
    let dd_dy = dpdy(in_d);
";
const DEPTH_SLOPE: &str = graph::DEPTH_SLOPE_WGSL;
const OCTAHEDRAL: &str = graph::OCTAHEDRAL_WGSL;

/// Why a Shade pass that asks for the compute (deferred) schedule runs forward, or None:
/// what the G-buffer does not carry, the screen-space derivatives of a light sample's view
/// (its `depth_slope`, the footprint of its implicit-LOD `sample`).
pub fn shade_refusal(ir: &Program, pass: &IrPass) -> Option<String> {
    let IrPassKind::Shade { visibility } = pass.kind else { return None };
    let arena = &ir.ir.arena;
    // the per-sample lookups and inputs
    arena.postorder(&[visibility]).into_iter().find_map(|h| {
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

/// Whether a Shade pass runs deferred: its schedule asks for compute and nothing refuses it
/// ([`shade_refusal`]).
pub fn shade_is_deferred(ir: &Program, pass: &IrPass) -> bool {
    pass.schedule == Schedule::Compute && shade_refusal(ir, pass).is_none()
}

/// A Shade pass: forward, one camera raster whose fragments evaluate the visibility; or
/// deferred (the compute schedule), a camera raster writing the G-buffer
/// ([`graph::GBUFFER`]) and then one compute invocation per pixel evaluating it from there.
/// Both compute the receiver's inputs the same way from the same values, except that the
/// deferred form reads the normal through an octahedral f32 encoding and the footprint of
/// implicit-LOD lookups at F16.
fn shade(ir: &Program, pass: &IrPass, visibility: ExprId, split: Split) -> Result<(String, Vec<Step>), Diagnostic> {
    let deferred = shade_is_deferred(ir, pass);
    let mut em = Emitter::new(ir, Site::Receiver, pass.reads.clone());
    em.split = split;
    em.deferred = deferred;
    let v = em.emit(visibility)?;
    let mut s = header(ir, pass);
    s.push_str(&em.declarations(ir));
    let entry = if deferred { "cs_shade" } else { "fs_shade" };
    let (functions, body) = em.finish(entry);
    s.push_str(&functions);
    s.push_str(SHADE_VARYING);
    let prologues: String = em.views.iter().map(|(&k, used)| sample_prologue(k, used)).collect();
    let receiver = shade_receiver(ir.ir.specialised.as_ref().map(|s| s.facts.light.is_distant()));
    // the `pixel` input, where the code reads it
    let uses_pixel = body.contains("in_pixel") || functions.contains("in_pixel");
    let pixel = |from: &str| {
        if uses_pixel {
            format!("    let in_pixel = {from};\n")
        } else {
            String::new()
        }
    };
    let outputs = |store: &dyn Fn(&str, &str) -> String| {
        format!(
            "    // outputs stay finite and in [0, 1]; a receiver facing away from the light's centre
    // is shadowed by its own surface
    let raw = {v};
    let vis = select(select(clamp(raw, 0.0, 1.0), 1.0, raw != raw), 0.0, in_ndotl <= 0.0);
    let lambert = max(in_ndotl, 0.0);
{}{}{}{}",
            store("visibility", "vec4<f32>(vis, 0.0, 0.0, 1.0)"),
            store("color", graph::SHADE_COLOR_WGSL),
            store("position", "vec4<f32>(in.world, 1.0)"),
            store("normal", "vec4<f32>(n, 0.0)"),
        )
    };
    let step = |vertex: Option<&str>, fragment: Option<&str>, compute: Option<&str>, draw: Draw, reads: bool| Step {
        vertex: vertex.map(str::to_string),
        fragment: fragment.map(str::to_string),
        compute: compute.map(str::to_string),
        draw,
        reads: if reads { em.graph_bindings() } else { vec![] },
        writes: vec![],
        params: reads && em.uses_params,
        sampler: reads && em.uses_sampler,
        light_samples: reads && !em.views.is_empty(),
        cost: OpCount::default(),
    };
    if !deferred {
        let _ = write!(
            s,
            "
// visibility (r32float), shaded colour (rgba8unorm), world position (rgba32float) and
// world normal (rgba16float): 36 bytes per sample as WebGPU counts them (rgba8unorm 8),
// above its default limit of 32: a host's device raises max_color_attachment_bytes_per_sample.
struct ShadeOut {{
    @location(0) visibility: vec4<f32>,
    @location(1) color: vec4<f32>,
    @location(2) position: vec4<f32>,
    @location(3) normal: vec4<f32>,
}}
{SHADE_VERTEX}
@fragment
fn fs_shade(in: ShadeVarying) -> ShadeOut {{
{SHADE_NORMAL}    let world = vec4<f32>(in.world, 1.0);
{receiver}{SHADE_SLOPE}{DEPTH_SLOPE}{}{prologues}{body}{}    return out;
}}
",
            pixel("floor(in.clip.xy)"),
            outputs(&|field, value| {
                let decl = if field == "visibility" { "    var out: ShadeOut;\n" } else { "" };
                format!("{decl}    out.{field} = {value};\n")
            })
        );
        let forward = step(Some("vs_shade"), Some("fs_shade"), None, Draw::SceneFromCamera, true);
        return Ok((s, vec![forward]));
    }
    s.push_str(SHADE_VERTEX);
    let _ = write!(
        s,
        "
// The G-buffer (sshc_graph::GBUFFER): world position and the centre view's depth slope,
// the normal (octahedral, f32), the footprint of the centre view's uv (f16).
struct GBufferOut {{
    @location(0) world: vec4<f32>,
    @location(1) normal: vec2<f32>,
    @location(2) duv: vec4<f32>,
}}

{OCTAHEDRAL}
@fragment
fn fs_gbuffer(in: ShadeVarying) -> GBufferOut {{
{SHADE_NORMAL}    let world = vec4<f32>(in.world, 1.0);
    let in_d = (-(frame.light_view * world).z - frame.depth_range.x) * frame.depth_range.z;
    let light_clip = frame.light_view_proj * world;
    let in_uv = light_clip.xy / light_clip.w * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5);
{SHADE_SLOPE}{DEPTH_SLOPE}    var out: GBufferOut;
    out.world = vec4<f32>(in.world, in_depth_slope);
    out.normal = octahedral(n);
    out.duv = vec4<f32>(duv_dx, duv_dy);
    return out;
}}

// The camera outputs (sshc_graph::CAMERA_OUTPUTS) and the G-buffer.
@group(2) @binding(0) var o_visibility: texture_storage_2d_array<r32float, write>;
@group(2) @binding(1) var o_color: texture_storage_2d_array<rgba8unorm, write>;
@group(2) @binding(2) var o_position: texture_storage_2d_array<rgba32float, write>;
@group(2) @binding(3) var o_normal: texture_storage_2d_array<rgba16float, write>;
@group(3) @binding(0) var g_world: texture_2d<f32>;
@group(3) @binding(1) var g_normal: texture_2d<f32>;
@group(3) @binding(2) var g_duv: texture_2d<f32>;

@compute @workgroup_size({wg}, {wg})
fn cs_shade(@builtin(global_invocation_id) id: vec3<u32>) {{
    // invocations past the target's edge store nothing
    if any(id.xy >= textureDimensions(o_visibility)) {{
        return;
    }}
    let pixel = vec2<i32>(id.xy);
    let gbuffer = textureLoad(g_world, pixel, 0i);
    // where the camera sees no surface (the G-buffer's clear value has w = -1): the forward
    // form's clear values, visibility 1, a dark background, position and normal NaN
    if gbuffer.w < 0.0 {{
        let nan = bitcast<f32>(0x7fc00000u);
        textureStore(o_visibility, pixel, 0i, vec4<f32>(1.0, 0.0, 0.0, 1.0));
        textureStore(o_color, pixel, 0i, vec4<f32>(0.02, 0.02, 0.03, 1.0));
        textureStore(o_position, pixel, 0i, vec4<f32>(nan));
        textureStore(o_normal, pixel, 0i, vec4<f32>(nan));
        return;
    }}
    let in = ShadeVarying(vec4<f32>(0.0), gbuffer.xyz, vec3<f32>(0.0));
    let n = from_octahedral(textureLoad(g_normal, pixel, 0i).xy);
    let world = vec4<f32>(in.world, 1.0);
{receiver}    let in_depth_slope = gbuffer.w;
    let footprint = textureLoad(g_duv, pixel, 0i);
    let in_duv_dx = footprint.xy;
    let in_duv_dy = footprint.zw;
{}{prologues}{body}{}}}
",
        pixel("vec2<f32>(pixel)"),
        outputs(&|field, value| format!("    textureStore(o_{field}, pixel, 0i, {value});\n")),
        wg = graph::TEXEL_WORKGROUP,
    );
    let gbuffer = step(Some("vs_shade"), Some("fs_gbuffer"), None, Draw::CameraGBuffer, false);
    let pixels = step(None, None, Some("cs_shade"), Draw::ComputePixels, true);
    Ok((s, vec![gbuffer, pixels]))
}

/// Parse and validate every module with naga, and count each entry point's operations.
fn validate_all(modules: &mut [Module]) -> Result<(), Diagnostics> {
    let mut diags = Diagnostics::default();
    for m in modules.iter_mut() {
        match crate::back::validate(&m.source) {
            Ok(module) => {
                for step in &mut m.steps {
                    let entry = step.fragment.clone().or_else(|| step.compute.clone());
                    if let Some(e) = entry {
                        step.cost = crate::back::count_ops(&module, &e);
                    }
                }
            }
            Err(msg) => diags.push(internal(format!("generated WGSL for `{}` does not validate: {msg}", m.file))),
        }
    }
    diags.check()
}
