//! The expression emitter: straight-line WGSL for a set of expression roots, in operand
//! order, one `let` per shared operation (the arena already merged equal
//! sub-expressions), texture reads of one texel of one layer fetched once and shared by
//! its channels. It records what the body used (bindings, params, the sampler, the
//! light samples' views) for the module's declarations and the graph's steps. An
//! operation on constants that did not fold (a division by zero, the log of a negative
//! number) is refused here, where it is met.

use crate::back::internal;
use crate::back::parts::{self, Line, Split};
use crate::back::summed_area::{TableCode, box_lookup, sat_read, table_code, table_decode, texel_read};
use crate::back::text::{COMP, decode_expr, f32_lit, i32_lit, params_struct};
use crate::builtins::{Func, Input, SampleFn, SampleWgsl, Sig, Ty};
use crate::diag::{Diagnostic, Phase};
use crate::front::ast::ConstValue;
use crate::front::expr::{BinOp, UnOp};
use crate::ir::{ChannelId, Encode, ExprId, Node, Program, ResId};
use crate::pack::table_source;
use sshc_graph::{self as graph, Binding, FRAME_WGSL, View};
use std::collections::HashMap;
use std::fmt::Write as _;

/// Where expressions are evaluated.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Site {
    /// Per shadow-map texel (`texel` is the integer coordinate).
    Map,
    /// Per fragment of a Geometry pass's primitives (`texel` is the fragment's shadow-map
    /// texel; the geometry inputs are `in_*` locals).
    Geometry,
    /// Per camera pixel in the Shade pass.
    Receiver,
}

/// Stands for the entry's name in the functions a long arm is split into, until
/// [`Emitter::finish`] knows it (entries of one module have different names).
const ARM_ENTRY: &str = "sshc_arm_of_entry";

/// Emits straight-line WGSL for a set of expression roots.
pub(crate) struct Emitter<'a> {
    ir: &'a Program<'a>,
    site: Site,
    body: Vec<Line>,
    /// What the code after the body reads: every value `emit` returned (a name, or an
    /// expression of names).
    roots: std::collections::HashSet<String>,
    /// Where long bodies are split into functions.
    pub(crate) split: Split,
    names: HashMap<ExprId, String>,
    /// The WGSL type of every `let` and branch `var` emitted, by name (names are unique in
    /// an entry): what a split arm's functions take as arguments from the enclosing scope.
    let_types: HashMap<String, &'static str>,
    /// Functions long arms were split into ([`Self::branch`]), named with [`ARM_ENTRY`]
    /// for the entry's name, which [`Self::finish`] puts in.
    arm_functions: String,
    fetches: HashMap<String, String>,
    /// Textures this module reads: (name, binding).
    pub(crate) bindings: Vec<(String, View)>,
    /// Of those, the summed-area tables (storage buffers) and what they sum.
    tables: Vec<(String, TableCode)>,
    /// The tables read by box lookups, and by `nearest` (each WGSL helper written once, where used).
    table_boxes: std::collections::BTreeSet<String>,
    table_texels: std::collections::BTreeSet<String>,
    pub(crate) uses_params: bool,
    pub(crate) uses_sampler: bool,
    /// The body calls the mip-chain box lookup's WGSL function (`builtins::MIP_BOX_WGSL`).
    uses_mip_box: bool,
    /// Map side: the resources the pass reads.
    reads: Vec<ResId>,
    counter: usize,
    /// Receiver side: the light samples whose views `at_sample` used, with the `in_*`
    /// locals of each view the body reads (the prologue computes only those).
    pub(crate) views: std::collections::BTreeMap<u8, std::collections::BTreeSet<Input>>,
    /// Map and geometry side, in a per-sample pass: per-sample resources are read at the
    /// layer block of the view being rendered (`frame.sample.x`).
    pub(crate) per_sample_pass: bool,
    /// Receiver side, in a deferred Shade's compute step: implicit-LOD lookups take their
    /// footprint from the G-buffer (`textureSampleGrad`), compute stages having no
    /// screen-space derivatives.
    pub(crate) deferred: bool,
}

impl<'a> Emitter<'a> {
    pub(crate) fn new(ir: &'a Program<'a>, site: Site, reads: Vec<ResId>) -> Self {
        Emitter {
            ir,
            site,
            body: Vec::new(),
            roots: Default::default(),
            split: Split::default(),
            names: HashMap::new(),
            let_types: HashMap::new(),
            arm_functions: String::new(),
            fetches: HashMap::new(),
            bindings: vec![],
            tables: vec![],
            table_boxes: Default::default(),
            table_texels: Default::default(),
            uses_params: false,
            uses_sampler: false,
            uses_mip_box: false,
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

    pub(crate) fn binding(&mut self, texture: &str, view: View) -> String {
        if !self.bindings.iter().any(|(n, _)| n == texture) {
            self.bindings.push((texture.to_string(), view));
        }
        format!("t_{texture}")
    }

    fn fresh(&mut self, prefix: &str) -> String {
        self.counter += 1;
        format!("{prefix}{}", self.counter)
    }

    pub(crate) fn line(&mut self, s: &str) {
        self.body.push(Line::Raw(s.to_string()));
    }

    fn let_line(&mut self, name: &str, ty: &'static str, rhs: String) {
        self.let_types.insert(name.to_string(), ty);
        self.body.push(Line::Let {
            name: name.to_string(),
            ty,
            rhs,
        });
    }

    /// The body's text and the functions it calls (long bodies are split: `back::parts`).
    /// `entry` names the entry point.
    pub(crate) fn finish(&self, entry: &str) -> (String, String) {
        let (functions, body) = parts::split(&self.body, entry, &self.roots, self.split, &|_| None);
        if self.arm_functions.is_empty() {
            return (functions, body);
        }
        (
            format!("{}{functions}", self.arm_functions).replace(ARM_ENTRY, entry),
            body.replace(ARM_ENTRY, entry),
        )
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

    pub(crate) fn emit(&mut self, root: ExprId) -> Result<String, Diagnostic> {
        self.emit_at(root)?;
        let name = self.names[&root].clone();
        self.roots.insert(name.clone());
        Ok(name)
    }

    /// Emit `root` and every operand not yet named, in operand order. Below a branch
    /// (`if c { t } else { f }`: `Func::Branch`), only what is read whichever arm is
    /// taken is emitted here: each arm's own operations go inside the `if` ([`Self::branch`]).
    fn emit_at(&mut self, root: ExprId) -> Result<(), Diagnostic> {
        let a = &self.ir.arena;
        let order: Vec<ExprId> = a.postorder_until(&[root], |h| self.names.contains_key(&h));
        let branches = order.iter().any(|h| matches!(a.node(*h), Node::Call(Func::Branch, _)));
        let here = if branches { Some(self.unconditional(root)) } else { None };
        for h in order {
            if self.names.contains_key(&h) || here.as_ref().is_some_and(|u| !u.contains(&h)) {
                continue;
            }
            if let Node::Call(Func::Branch, args) = a.node(h)
                && let [f, t, c] = args[..]
            {
                self.branch(h, f, t, c)?;
                continue;
            }
            let e = self.expr(h)?;
            let leaf = matches!(
                a.node(h),
                Node::F32(_) | Node::I32(_) | Node::U32(_) | Node::Bool(_) | Node::Param(_) | Node::Input(..) | Node::Channel(..)
            );
            if leaf {
                self.names.insert(h, e);
            } else {
                let name = format!("e{}", h.index());
                self.let_line(&name, a.ty(h).wgsl(), e);
                self.names.insert(h, name);
            }
        }
        Ok(())
    }

    /// What `root` reads whichever way its branches go (not yet named): every operand, but
    /// only the condition of a branch, and every lookup with an implicit level of detail
    /// with what it reads (WGSL allows screen-space derivatives in uniform control flow
    /// only; `check` refuses such lookups written inside an arm, so these were bound
    /// before the `if` with `let`).
    fn unconditional(&self, root: ExprId) -> std::collections::HashSet<ExprId> {
        let a = &self.ir.arena;
        let implicit = |h: &ExprId| matches!(a.node(*h), Node::Sample { how: SampleFn::Sample, .. });
        let mut stack: Vec<ExprId> = vec![root];
        stack.extend(
            a.postorder_until(&[root], |h| self.names.contains_key(&h))
                .into_iter()
                .filter(implicit),
        );
        let mut out = std::collections::HashSet::new();
        while let Some(h) = stack.pop() {
            if self.names.contains_key(&h) || !out.insert(h) {
                continue;
            }
            if let Node::Call(Func::Branch, args) = a.node(h) {
                stack.push(args[2]);
            } else {
                stack.extend(a.operands(h));
            }
        }
        out
    }

    /// `if c { t } else { f }` as a WGSL `if` assigning a `var` named as the node: what
    /// both arms read first, then each arm's own operations inside its block (their names
    /// are scoped to it, and forgotten after).
    fn branch(&mut self, h: ExprId, f: ExprId, t: ExprId, c: ExprId) -> Result<(), Diagnostic> {
        let a = &self.ir.arena;
        let named = |h: ExprId| self.names.contains_key(&h);
        let reach = |x: ExprId| -> std::collections::HashSet<ExprId> { a.postorder_until(&[x], named).into_iter().collect() };
        let (in_t, in_f) = (reach(t), reach(f));
        for s in a.postorder_until(&[t, f], named) {
            if in_t.contains(&s) && in_f.contains(&s) && !self.names.contains_key(&s) {
                self.emit_at(s)?;
            }
        }
        let name = format!("e{}", h.index());
        let ty = a.ty(h).wgsl();
        let mut text = format!("var {name}: {ty};\nif {} {{\n", self.n(c));
        for (side, arm, x) in [("t", "} else {\n", t), ("f", "}\n", f)] {
            let saved = (std::mem::take(&mut self.body), self.names.clone(), self.fetches.clone());
            self.emit_at(x)?;
            let value = self.names[&x].clone();
            let lines = std::mem::replace(&mut self.body, saved.0);
            (self.names, self.fetches) = (saved.1, saved.2);
            // a long arm is split into functions as a long body is (`back::parts`): naga
            // types an arm's expressions in its function's arena, so sixteen arms of a
            // 4,096-term series each took 10 s to parse (issue 48, item 4)
            let types = &self.let_types;
            let (functions, body) = parts::split(
                &lines,
                &format!("{ARM_ENTRY}_{name}{side}"),
                &std::collections::HashSet::from([value.clone()]),
                self.split,
                &|id| types.get(id).copied(),
            );
            self.arm_functions.push_str(&functions);
            text.push_str(&body);
            let _ = writeln!(text, "    {name} = {value};");
            text.push_str(arm);
        }
        self.let_types.insert(name.clone(), ty);
        self.body.push(Line::Branch {
            name: name.clone(),
            ty,
            text,
        });
        self.names.insert(h, name);
        Ok(())
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
                self.views.entry(k).or_default().insert(i);
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
                f.wgsl_call(&v, self.ir.arena.ty(h))
            }
        })
    }

    /// Map side: the value of a channel at this texel, read from the resource that carries it.
    pub(crate) fn load_map_channel(&mut self, c: ChannelId, [dx, dy]: [i32; 2]) -> Result<String, Diagnostic> {
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
        Ok(decode_expr(&format!("{v}.{}", COMP[comp as usize]), enc))
    }

    fn sample(&mut self, ch: ChannelId, res: ResId, how: SampleFn, args: &[ExprId], view: Option<u8>) -> Result<String, Diagnostic> {
        // the receiver's shadow-map coordinates and the texel under them, in the view read
        let (uv, base) = match view {
            Some(k) => {
                self.views.entry(k).or_default().insert(Input::Uv);
                let uv = format!("in_uv_v{k}");
                let base = format!("vec2<i32>(floor({uv} * frame.shadow_size.xy - 0.5))");
                (uv, base)
            }
            None => ("in_uv".to_string(), "in_base".to_string()),
        };
        let (tex, layer, comp, enc) = self.locate(res, ch, View::All, view)?;
        let args: Vec<String> = args.iter().map(|a| self.n(*a).to_string()).collect();
        let key = format!("{tex}/{layer}/{how:?}/{}", args.join(","));
        let on_table = how.table_may_answer() && table_source(self.ir, res).is_some();
        // what a table sums, and its slot (to decode the component read)
        let table = if on_table || how.reads_table() {
            if table_source(self.ir, res).is_none() {
                return Err(internal("box lookup of a texture"));
            }
            let slot = *self.ir.resources[res]
                .slot_of(ch)
                .ok_or_else(|| internal("a table lookup of a channel it lacks"))?;
            Some((table_code(self.ir, res, slot.texture)?, slot))
        } else {
            None
        };
        let v = match self.fetches.get(&key) {
            Some(v) => v.clone(),
            None => {
                let v = self.fresh("s");
                let call = match how.desc().wgsl {
                    _ if let Some((code, _)) = table => {
                        let name = tex.trim_start_matches("t_").to_string();
                        if !self.tables.iter().any(|(n, _)| *n == name) {
                            self.tables.push((name.clone(), code));
                        }
                        let at = |du: &str, dv: &str| format!("{uv} + vec2<f32>({du}, {dv})");
                        match how {
                            SampleFn::Box | SampleFn::BoxAt => {
                                self.table_boxes.insert(name.clone());
                                let (centre, w) = if how == SampleFn::BoxAt {
                                    (at(&args[0], &args[1]), &args[2..])
                                } else {
                                    (uv.clone(), &args[..])
                                };
                                format!("box_{name}({centre}, vec2<f32>({}, {}), {layer})", w[0], w[1])
                            }
                            SampleFn::NearestAt => {
                                self.table_texels.insert(name.clone());
                                format!("texel_{name}({}, {layer})", at(&args[0], &args[1]))
                            }
                            SampleFn::Nearest => {
                                self.table_texels.insert(name.clone());
                                format!("texel_{name}({uv}, {layer})")
                            }
                            SampleFn::Sample
                            | SampleFn::SampleLod
                            | SampleFn::SampleWidth
                            | SampleFn::Fetch
                            | SampleFn::SampleAt
                            | SampleFn::SampleWidthAt
                            | SampleFn::NearestLevel
                            | SampleFn::NearestLevelAt
                            | SampleFn::MipBox
                            | SampleFn::MipBoxAt => return Err(internal("a texture lookup of a summed-area table")),
                        }
                    }
                    // `shade_refusal` keeps per-sample implicit-LOD lookups forward
                    SampleWgsl::Texture { sampler, .. } if self.deferred && how == SampleFn::Sample && view.is_none() => {
                        self.uses_sampler |= sampler;
                        format!("textureSampleGrad({tex}, smp, in_uv, {layer}, in_duv_dx, in_duv_dy)")
                    }
                    SampleWgsl::Texture { sampler, read } => {
                        self.uses_sampler |= sampler;
                        self.uses_mip_box |= how.needs_mean_chain();
                        read(&tex, &layer, &uv, &base, &args)
                    }
                    // reads_table holds for every lookup of this form
                    SampleWgsl::SummedAreaTable => return Err(internal("a table lookup left unread")),
                };
                // every lookup returns the texel's four components
                self.let_line(&v, "vec4<f32>", call);
                self.fetches.insert(key, v.clone());
                v
            }
        };
        let x = format!("{v}.{}", COMP[comp as usize]);
        Ok(match table {
            Some((code, slot)) => decode_expr(&table_decode(code, &slot, &x), enc),
            None => decode_expr(&x, enc),
        })
    }

    /// Module-level declarations for what the body used.
    pub(crate) fn declarations(&self, ir: &Program) -> String {
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
        if self.uses_mip_box {
            s.push_str(crate::builtins::MIP_BOX_WGSL);
        }
        for (i, (name, _)) in self.bindings.iter().enumerate() {
            match self.tables.iter().find(|(n, _)| n == name) {
                Some((_, code)) => {
                    let _ = writeln!(s, "@group(1) @binding({i}) var<storage, read> t_{name}: array<{}>;", code.elem());
                    if self.table_boxes.contains(name) {
                        s.push_str(&box_lookup(name, *code));
                    } else {
                        s.push_str(&sat_read(name, *code));
                    }
                    if self.table_texels.contains(name) {
                        s.push_str(&texel_read(name, *code));
                    }
                }
                None => {
                    let _ = writeln!(s, "@group(1) @binding({i}) var t_{name}: texture_2d_array<f32>;");
                }
            }
        }
        s
    }

    pub(crate) fn graph_bindings(&self) -> Vec<Binding> {
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
