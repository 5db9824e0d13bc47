//! Phase `resolve`: names become indices. Declarations are collected (duplicates and
//! reserved names refused), command-line overrides (`--set`, `--precision`) are applied,
//! and every resource gets the pass that writes it.

use crate::diag::{Diagnostic, Diagnostics, Phase};
use crate::front::ast::*;
use crate::front::parse::closest;
use crate::span::{Span, Spanned};
use crate::{CompileOptions, builtins};
use indexmap::IndexMap;

/// A resource: named image written by exactly one pass.
#[derive(Clone, Debug)]
pub struct Resource {
    pub name: String,
    pub writer: usize,
    pub span: Span,
}

/// What a name in a resource's channel list stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Item {
    Channel(usize),
    Expansion(usize),
}

#[derive(Debug)]
pub struct Symbols<'a> {
    pub t: &'a Technique,
    pub params: IndexMap<String, usize>,
    pub channels: IndexMap<String, usize>,
    pub expansions: IndexMap<String, usize>,
    /// The technique's functions, by name (index into `Technique::functions`).
    pub functions: IndexMap<String, usize>,
    /// The technique's constant arrays, by name (index into `Technique::arrays`).
    pub arrays: IndexMap<String, usize>,
    pub passes: IndexMap<String, usize>,
    pub resources: IndexMap<String, Resource>,
    /// Parameter values after `--set` overrides, with the span that set them.
    pub values: Vec<Spanned<ConstValue>>,
    /// Whether a value came from the command line.
    pub overridden: Vec<bool>,
    /// Channel and expansion precisions after `--precision` overrides.
    pub channel_precision: Vec<Precision>,
    pub expansion_precision: Vec<Precision>,
    /// Precisions left to the compiler (`Auto` in the file or `--precision NAME=auto`).
    pub channel_auto: Vec<bool>,
    pub expansion_auto: Vec<bool>,
    /// Per pass: its schedule after `--schedule` overrides (None: the compiler's default).
    pub schedules: Vec<Option<Schedule>>,
    /// `--scene`: the facts to specialise for, admitted by the technique's `light:` list.
    pub scene: Option<sshc_graph::SceneFacts>,
    /// Whether the Shade's debug outputs are compiled (`CompileOptions::debug`).
    pub debug: bool,
}

impl<'a> Symbols<'a> {
    /// A copy sharing the technique (for re-lowering with other param values).
    pub fn clone_shallow(&self) -> Symbols<'a> {
        Symbols {
            t: self.t,
            params: self.params.clone(),
            channels: self.channels.clone(),
            expansions: self.expansions.clone(),
            functions: self.functions.clone(),
            arrays: self.arrays.clone(),
            passes: self.passes.clone(),
            resources: self.resources.clone(),
            values: self.values.clone(),
            overridden: self.overridden.clone(),
            channel_precision: self.channel_precision.clone(),
            expansion_precision: self.expansion_precision.clone(),
            channel_auto: self.channel_auto.clone(),
            expansion_auto: self.expansion_auto.clone(),
            schedules: self.schedules.clone(),
            scene: self.scene.clone(),
            debug: self.debug,
        }
    }

    pub fn param(&self, name: &str) -> Option<(usize, &Param)> {
        self.params.get(name).map(|&i| (i, &self.t.params[i]))
    }

    /// Every name an expression may refer to, for "did you mean" hints.
    pub fn visible_names(&self) -> Vec<&str> {
        let mut v: Vec<&str> = self.params.keys().map(String::as_str).collect();
        v.extend(self.channels.keys().map(String::as_str));
        v.extend(self.expansions.keys().map(String::as_str));
        v.extend(builtins::Input::ALL.iter().map(|i| i.name()));
        v.extend(["PI", "E"]);
        v
    }
}

pub fn resolve<'a>(t: &'a Technique, opts: &CompileOptions) -> Result<Symbols<'a>, Diagnostics> {
    let mut diags = Diagnostics::default();
    let mut seen: IndexMap<String, Span> = IndexMap::new();
    let mut declare = |name: &Spanned<String>, what: &str, diags: &mut Diagnostics| {
        if builtins::is_reserved(&name.value) {
            diags.push(
                Diagnostic::error(
                    Phase::Resolve,
                    format!("`{}` is a built-in name and cannot name a {what}", name.value),
                )
                .at(name.span, "reserved")
                .help("choose another name"),
            );
        } else if let Some(first) = seen.get(&name.value) {
            diags.push(
                Diagnostic::error(Phase::Resolve, format!("duplicate name `{}`", name.value))
                    .at(name.span, format!("{what} `{}` declared again here", name.value))
                    .also(*first, "first declared here")
                    .help("params, channels, expansions, functions and arrays share one namespace; rename one of them"),
            );
        } else {
            seen.insert(name.value.clone(), name.span);
        }
    };
    let mut params = IndexMap::new();
    for (i, p) in t.params.iter().enumerate() {
        declare(&p.name, "param", &mut diags);
        // a runtime param is a field of the WGSL uniform block `params`: its name must be
        // a WGSL identifier (a fixed one is folded into the code and never named there)
        let name = &p.name.value;
        if !p.fixed && (naga::keywords::wgsl::RESERVED.contains(&name.as_str()) || name.starts_with("__")) {
            diags.push(
                Diagnostic::error(Phase::Resolve, format!("`{name}` cannot name a runtime param: WGSL reserves it"))
                    .at(p.name.span, "reserved in WGSL")
                    .help("a runtime param becomes a field of the shaders' uniform block; rename it, or make it `fixed: true`"),
            );
        }
        params.entry(p.name.value.clone()).or_insert(i);
    }
    let mut channels = IndexMap::new();
    for (i, c) in t.channels.iter().enumerate() {
        declare(&c.name, "channel", &mut diags);
        channels.entry(c.name.value.clone()).or_insert(i);
    }
    let mut expansions = IndexMap::new();
    for (i, e) in t.expansions.iter().enumerate() {
        declare(&e.name, "expansion", &mut diags);
        expansions.entry(e.name.value.clone()).or_insert(i);
    }
    let mut functions = IndexMap::new();
    for (i, f) in t.functions.iter().enumerate() {
        declare(&f.name, "function", &mut diags);
        functions.entry(f.name.value.clone()).or_insert(i);
        let mut names: Vec<&Name> = Vec::new();
        for (p, _) in &f.params {
            if builtins::is_reserved(&p.value) {
                diags.push(
                    Diagnostic::error(
                        Phase::Resolve,
                        format!("`{}` is a built-in name and cannot name a parameter", p.value),
                    )
                    .at(p.span, "reserved")
                    .help("choose another name"),
                );
            } else if let Some(first) = names.iter().find(|n| n.value == p.value) {
                diags.push(
                    Diagnostic::error(
                        Phase::Resolve,
                        format!("function `{}` has two parameters named `{}`", f.name.value, p.value),
                    )
                    .at(p.span, "declared again here")
                    .also(first.span, "first declared here"),
                );
            }
            names.push(p);
        }
    }
    let mut arrays = IndexMap::new();
    for (i, a) in t.arrays.iter().enumerate() {
        declare(&a.name, "array", &mut diags);
        arrays.entry(a.name.value.clone()).or_insert(i);
    }

    let mut passes = IndexMap::new();
    let mut resources: IndexMap<String, Resource> = IndexMap::new();
    for (i, p) in t.passes.iter().enumerate() {
        if let Some(&first) = passes.get(&p.name.value) {
            let first: &Pass = &t.passes[first];
            diags.push(
                Diagnostic::error(Phase::Resolve, format!("duplicate pass name `{}`", p.name.value))
                    .at(p.name.span, "declared again here")
                    .also(first.name.span, "first declared here"),
            );
        } else {
            passes.insert(p.name.value.clone(), i);
        }
        if let Some(w) = p.kind.writes() {
            if let Some(prev) = resources.get(&w.value) {
                diags.push(
                    Diagnostic::error(Phase::Resolve, format!("resource `{}` is written by two passes", w.value))
                        .at(w.span, format!("written again by `{}`", p.name.value))
                        .also(prev.span, "first written here")
                        .help("every pass writes a resource of its own name; give this output a new name"),
                );
            } else {
                resources.insert(
                    w.value.clone(),
                    Resource {
                        name: w.value.clone(),
                        writer: i,
                        span: w.span,
                    },
                );
            }
        }
    }

    // Debug outputs: one name each, and a texture name (`debug_<name>`) no resource's
    // textures (`<resource>` or `<resource>_<suffix>`) can take.
    for p in &t.passes {
        let PassKind::Shade { debug, .. } = &p.kind else { continue };
        if let Some(extra) = debug.get(sshc_graph::MAX_DEBUG_OUTPUTS) {
            diags.push(
                Diagnostic::error(
                    Phase::Resolve,
                    format!(
                        "{} debug outputs: a Shade pass has at most {}",
                        debug.len(),
                        sshc_graph::MAX_DEBUG_OUTPUTS
                    ),
                )
                .at(extra.name.span, "one too many")
                .note("a forward Shade renders each as a colour attachment after its four camera outputs, and WebGPU has 8")
                .help("show the others in another build, or put up to four scalars in one `vec4(...)`"),
            );
        }
        for (i, o) in debug.iter().enumerate() {
            if let Some(first) = debug[..i].iter().find(|f| f.name.value == o.name.value) {
                diags.push(
                    Diagnostic::error(Phase::Resolve, format!("two debug outputs are named `{}`", o.name.value))
                        .at(o.name.span, "named again here")
                        .also(first.name.span, "first named here")
                        .help("each debug output becomes a texture of its name: rename one of them"),
                );
                continue;
            }
            let texture = debug_texture(&o.name.value);
            if let Some(r) = resources
                .values()
                .find(|r| texture == r.name || texture.strip_prefix(r.name.as_str()).is_some_and(|s| s.starts_with('_')))
            {
                diags.push(
                    Diagnostic::error(
                        Phase::Resolve,
                        format!(
                            "debug output `{}` would be texture `{texture}`, a name resource `{}`'s textures may take",
                            o.name.value, r.name
                        ),
                    )
                    .at(o.name.span, format!("becomes texture `{texture}`"))
                    .also(r.span, "this resource's textures are named after it")
                    .help("rename the debug output or the resource"),
                );
            }
        }
    }

    // Channel names listed by Depth, Map and Geometry passes must be declared.
    for p in &t.passes {
        let listed: Vec<&Name> = match &p.kind {
            PassKind::Depth { channel, .. } => vec![channel],
            PassKind::Map { channels: c, .. } | PassKind::Geometry { channels: c, .. } => c.iter().collect(),
            PassKind::Filter { .. } | PassKind::Mipmap { .. } | PassKind::SummedArea { .. } | PassKind::Shade { .. } => vec![],
        };
        for n in listed {
            if !channels.contains_key(&n.value) && !expansions.contains_key(&n.value) {
                let cands: Vec<&str> = channels.keys().chain(expansions.keys()).map(String::as_str).collect();
                let mut d = Diagnostic::error(Phase::Resolve, format!("unknown channel `{}`", n.value))
                    .at(n.span, "not declared in `channels` or `expansions`");
                if let Some(s) = closest(&n.value, &cands) {
                    d = d.help(format!("did you mean `{s}`?"));
                }
                diags.push(d);
            }
        }
    }

    // Overrides from the command line.
    let mut values: Vec<Spanned<ConstValue>> = t.params.iter().map(|p| p.default.clone()).collect();
    let mut overridden = vec![false; t.params.len()];
    for (name, text) in &opts.set {
        let Some(&i) = params.get(name) else {
            let cands: Vec<&str> = params.keys().map(String::as_str).collect();
            let mut d = Diagnostic::error(Phase::Cli, format!("`--set {name}=...`: the technique has no param `{name}`"));
            if let Some(s) = closest(name, &cands) {
                d = d.help(format!("did you mean `{s}`?"));
            } else {
                d = d.note(format!("its params are: {}", cands.join(", ")));
            }
            diags.push(d);
            continue;
        };
        let p = &t.params[i];
        let parsed = crate::front::ron::parse(text)
            .map_err(|_| ())
            .and_then(|node| crate::front::parse::const_value(&node, p.ty.value).map_err(|_| ()));
        match parsed {
            Ok(v) => {
                values[i] = Spanned::new(v.value, p.default.span);
                overridden[i] = true;
            }
            Err(()) => diags.push(
                Diagnostic::error(
                    Phase::Cli,
                    format!("`--set {name}={text}`: expected a value of type {}", p.ty.value.name()),
                )
                .at(p.ty.span, format!("`{name}` is declared {} here", p.ty.value.name())),
            ),
        }
    }
    let mut channel_precision: Vec<Precision> = t.channels.iter().map(|c| c.precision.value).collect();
    let mut expansion_precision: Vec<Precision> = t.expansions.iter().map(|e| e.precision.value).collect();
    let mut channel_auto: Vec<bool> = t.channels.iter().map(|c| c.precision_auto).collect();
    let mut expansion_auto: Vec<bool> = t.expansions.iter().map(|e| e.precision_auto).collect();
    for (name, text) in &opts.precision {
        // `auto`: left to the compiler (F32 until it chooses)
        let auto = text.trim().eq_ignore_ascii_case("auto");
        let Some(p) = Precision::parse(text).or(auto.then_some(Precision::F32)) else {
            diags.push(
                Diagnostic::error(Phase::Cli, format!("`--precision {name}={text}`: unknown precision"))
                    .note("expected one of: unorm8, unorm16, f16, f32, auto"),
            );
            continue;
        };
        // `a,b,c=...` sets several at once (a sweep axis over a packed texture's channels)
        for one in name.split(',').map(str::trim) {
            if let Some(&i) = channels.get(one) {
                channel_precision[i] = p;
                channel_auto[i] = auto;
            } else if let Some(&i) = expansions.get(one) {
                expansion_precision[i] = p;
                expansion_auto[i] = auto;
            } else {
                diags.push(Diagnostic::error(
                    Phase::Cli,
                    format!("`--precision {name}=...`: no channel or expansion named `{one}`"),
                ));
            }
        }
    }

    let mut schedules: Vec<Option<Schedule>> = t.passes.iter().map(|p| p.kind.schedule()).collect();
    for (name, text) in &opts.schedule {
        let Some(sch) = Schedule::parse(text) else {
            diags.push(
                Diagnostic::error(Phase::Cli, format!("`--schedule {name}={text}`: unknown schedule"))
                    .note("expected one of: fragment, compute"),
            );
            continue;
        };
        // `*` names every pass that has schedules (a sweep axis over a technique's schedules)
        let mut named = false;
        for (i, p) in t.passes.iter().enumerate() {
            if name != "*" && p.name.value != *name {
                continue;
            }
            named = true;
            if p.kind.schedulable() {
                schedules[i] = Some(sch);
            } else if name != "*" {
                diags.push(
                    Diagnostic::error(
                        Phase::Cli,
                        format!("`--schedule {name}={text}`: pass `{name}` is a {} pass", p.kind.kind_name()),
                    )
                    .at(p.kind_span, "declared here")
                    .note("only Map, Filter, Mipmap and Shade passes have schedules"),
                );
            }
        }
        if !named {
            diags.push(Diagnostic::error(
                Phase::Cli,
                format!("`--schedule {name}={text}`: no pass named `{name}`"),
            ));
        }
    }

    // A scene's light must be one the technique admits (an absent `light:` admits any).
    if let Some(facts) = &opts.scene {
        let admits = t.lights.is_empty() || t.lights.iter().any(|l| l.value.accepts(facts.light));
        // (`crate::admits` answers the same from the source, for the command line)
        if !admits {
            let names: Vec<&str> = t.lights.iter().filter_map(|l| l.value.kind()).map(|k| k.name()).collect();
            let span = t.lights.iter().map(|l| l.span).reduce(|a, b| a.join(b)).unwrap_or(t.name.span);
            diags.push(
                Diagnostic::error(
                    Phase::Resolve,
                    format!(
                        "technique `{}` does not admit the {} light of scene {}",
                        t.name.value,
                        facts.light.name(),
                        facts.scene
                    ),
                )
                .at(span, format!("admits {}", names.join(", ")))
                .note("specialising for a scene (`--scene`) checks the technique's `light:` list")
                .help(format!(
                    "add `{}` to `light:` where the technique handles such a light, or compile without `--scene`",
                    facts.light.name()
                )),
            );
        }
    }

    diags.check()?;
    Ok(Symbols {
        t,
        params,
        channels,
        expansions,
        functions,
        arrays,
        passes,
        resources,
        values,
        overridden,
        channel_precision,
        expansion_precision,
        channel_auto,
        expansion_auto,
        schedules,
        scene: opts.scene.clone(),
        debug: opts.debug,
    })
}

/// The texture a debug output is written to: `debug_<name>` (a name of the graph, and the
/// one `Inspect::read_debug` and `sshc render --dump` take).
pub fn debug_texture(name: &str) -> String {
    format!("{}{name}", sshc_graph::DEBUG_PREFIX)
}
