//! `sshc`: a compiler of real-time soft-shadow techniques.
//!
//! A technique written in RON (params, light model, channels, basis expansions, passes and
//! a visibility expression) is compiled through one module per phase:
//!
//! ```text
//! parse -> resolve -> check -> lower -> analyse -> pack -> schedule -> codegen -> emit
//! ```
//!
//! into naga-validated WGSL modules and a [`PassGraph`] of the runtime crate's schema.
//! Every error a technique file can cause is a [`Diagnostic`] with a span; nothing here
//! touches the GPU.

// Diagnostics travel on the cold error path; boxing them would only add noise.
#![allow(clippy::result_large_err)]
// A match on an enum names every variant, so adding one is a compile error everywhere it
// must be handled.
#![deny(clippy::wildcard_enum_match_arm)]

// The public API is what this file declares and re-exports, and the two facade modules
// `eval` and `tune`; every phase and data structure behind them is private to the crate
// (docs/architecture.md, "The public API").
mod analyse;
mod back;
mod builtins;
mod check;
mod consteval;
mod diag;
mod emit;
pub mod eval;
mod explain;
mod front;
mod handle;
mod interp;
mod interval;
mod ir;
mod lower;
mod pack;
mod ranges;
mod resolve;
mod rounding;
mod schedule;
mod span;
mod tables;
pub mod tune;
mod types;

pub use back::parts::Split;
pub use back::validate as validate_wgsl;
pub use diag::{Diagnostic, Diagnostics, Edit, Level, Phase};
pub use front::ast::Precision;
pub use pack::Limits;
pub use span::Span;
pub use sshc_graph::PassGraph;
pub use sshc_graph::cost::Cost;

use std::path::Path;

/// Phases after which `--dump-ir-after` can print the IR.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum DumpPhase {
    Parse,
    Resolve,
    Check,
    Lower,
    Analyse,
    Pack,
    Schedule,
    Codegen,
    Emit,
}

impl DumpPhase {
    /// Every phase, in the order the driver runs them (`Outcome::phases`).
    pub const ALL: [DumpPhase; 9] = [
        DumpPhase::Parse,
        DumpPhase::Resolve,
        DumpPhase::Check,
        DumpPhase::Lower,
        DumpPhase::Analyse,
        DumpPhase::Pack,
        DumpPhase::Schedule,
        DumpPhase::Codegen,
        DumpPhase::Emit,
    ];

    /// The phase's name on the command line (`--dump-ir-after NAME`).
    pub fn name(self) -> &'static str {
        match self {
            DumpPhase::Parse => "parse",
            DumpPhase::Resolve => "resolve",
            DumpPhase::Check => "check",
            DumpPhase::Lower => "lower",
            DumpPhase::Analyse => "analyse",
            DumpPhase::Pack => "pack",
            DumpPhase::Schedule => "schedule",
            DumpPhase::Codegen => "codegen",
            DumpPhase::Emit => "emit",
        }
    }
}

impl std::str::FromStr for DumpPhase {
    type Err = String;

    fn from_str(s: &str) -> Result<DumpPhase, String> {
        DumpPhase::ALL.into_iter().find(|p| p.name() == s).ok_or_else(|| {
            let names: Vec<&str> = DumpPhase::ALL.iter().map(|p| p.name()).collect();
            format!("unknown phase `{s}`: expected one of {}", names.join(", "))
        })
    }
}

#[derive(Clone, Debug, Default)]
pub struct CompileOptions {
    /// `--set NAME=VALUE` overrides of param values (RON literals).
    pub set: Vec<(String, String)>,
    /// `--precision NAME=P` overrides of channel or expansion precision.
    pub precision: Vec<(String, String)>,
    /// `--schedule PASS=S` overrides of a pass's schedule (`fragment`, `compute`; `*` for
    /// every Map, Filter and Mipmap pass).
    pub schedule: Vec<(String, String)>,
    pub limits: Limits,
    pub dump_after: Option<DumpPhase>,
    /// Where long generated bodies are split into functions ([`Split`]).
    pub split: Split,
    /// `--scene`: specialise for the scene's facts: refuse a scene light the
    /// technique's `light:` list does not admit, fold the light inputs that are 0 for it.
    pub scene: Option<sshc_graph::SceneFacts>,
    /// Estimate what storage rounding does to the visibility and warn above
    /// `rounding::WARN_ABOVE` (`sshc compile` and `explain` do). It runs only where a
    /// channel is stored below F32, and costs up to about 120 ms in a release build (CSSM,
    /// against 7 ms for the rest of its compilation; docs/language.md section 5), so a
    /// library compilation asks for it.
    pub rounding: bool,
    /// Compile the Shade's debug outputs (`debug: {...}`, `sshc compile --debug`): each
    /// becomes a camera-sized texture `debug_<name>` the Shade writes. Without it they are
    /// checked and then left out: the WGSL and the graph are those of a technique without
    /// them.
    pub debug: bool,
}

/// A compiled technique.
#[derive(Clone, Debug)]
pub struct Compiled {
    /// The IR as `lower` produced it (no later phase changes it).
    pub(crate) ir: ir::Ir,
    /// Its layout after `pack`: live resources and passes, placements, textures.
    pub(crate) layout: ir::Layout,
    /// The schedule each live pass runs in, as the `schedule` phase chose it: what codegen
    /// generated and `explain` reports.
    pub(crate) schedules: schedule::Schedules,
    pub graph: PassGraph,
    /// (file name, WGSL source), in pass order.
    pub shaders: Vec<(String, String)>,
    pub cost: Cost,
    pub warnings: Vec<Diagnostic>,
}

impl Compiled {
    /// The technique's name (`name:` in its file).
    pub fn technique(&self) -> &str {
        &self.ir.technique
    }

    /// What `sshc explain` prints: passes, resources and their formats, schedules, costs,
    /// the rounding estimate at each precision.
    pub fn explain(&self) -> String {
        explain::explain(self)
    }

    /// What specialising this (generic) compilation for a scene's facts changed, compared
    /// with `specialised` (`sshc explain --scene`).
    pub fn specialisation(&self, specialised: &Compiled) -> String {
        explain::specialisation(self, specialised)
    }

    /// The WGSL of the technique's `Params` uniform struct (what `sshc-shaders` embeds
    /// beside the shaders).
    pub fn params_struct(&self) -> String {
        back::wgsl::params_struct(&self.program())
    }

    /// The debug outputs checked and then left out of this build (compiled without
    /// `CompileOptions::debug`).
    pub fn debug_omitted(&self) -> &[String] {
        &self.ir.debug_omitted
    }

    /// The names a `--precision NAME=P` option takes: every channel (basis channels
    /// included), then every expansion.
    pub fn stored_names(&self) -> Vec<String> {
        let channels = self.ir.channels.iter().map(|c| c.name.clone());
        channels.chain(self.ir.expansions.iter().map(|e| e.name.clone())).collect()
    }

    /// Each live pass that has a schedule (Map, Filter, Mipmap, ...), with whether it runs
    /// as a compute shader: what `--schedule PASS=S` can change.
    pub fn schedules(&self) -> Vec<(String, bool)> {
        self.ir
            .passes
            .with_handles()
            .filter(|(id, _)| self.schedules.of(*id).is_some())
            .map(|(id, p)| (p.name.clone(), self.schedules.compute(id)))
            .collect()
    }

    /// The IR and its layout, as the back end and the CPU evaluation read them.
    pub(crate) fn program(&self) -> ir::Program<'_> {
        ir::Program::new(&self.ir, &self.layout)
    }
}

/// The result of a compilation with the IR dump that was asked for (also on failure).
pub struct Outcome {
    pub result: Result<Compiled, Diagnostics>,
    pub dump: Option<String>,
    /// The phases that ran to their end, in the order they ran.
    pub phases: Vec<DumpPhase>,
}

/// Stop after `check` (used by `sshc check`), or go all the way.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Until {
    Check,
    Emit,
}

pub use sshc_graph::SceneFacts;

/// Whether the technique's `light:` list admits a light of `kind` (an absent list, or
/// `Any`, admits every kind); true where the source does not parse, so that compiling it
/// reports the error.
pub fn admits(source: &str, kind: sshc_graph::LightKind) -> bool {
    match front::parse::parse(source) {
        Ok(t) => t.lights.is_empty() || t.lights.iter().any(|l| l.value.accepts(kind)),
        Err(_) => true,
    }
}

/// Compile technique source text.
pub fn compile_str(source: &str, opts: &CompileOptions) -> Result<Compiled, Diagnostics> {
    run(source, opts, Until::Emit).result
}

/// Compile, keeping the `--dump-ir-after` text.
pub fn compile_with_dump(source: &str, opts: &CompileOptions) -> Outcome {
    run(source, opts, Until::Emit)
}

/// Validate only: parse, resolve and check.
pub fn check_str(source: &str, opts: &CompileOptions) -> Result<(), Diagnostics> {
    check_with_dump(source, opts).0
}

/// Validate only, keeping the `--dump-ir-after` text of the phases that ran (parse, resolve, check).
pub fn check_with_dump(source: &str, opts: &CompileOptions) -> (Result<(), Diagnostics>, Option<String>) {
    let o = run(source, opts, Until::Check);
    let r = match o.result {
        Err(d) if d.is_empty() => Ok(()),
        Err(d) => Err(d),
        Ok(_) => Ok(()),
    };
    (r, o.dump)
}

/// Read and compile a technique file; errors are rendered against the file.
pub fn compile_file(path: &Path, opts: &CompileOptions) -> Result<Compiled, String> {
    let source = std::fs::read_to_string(path).map_err(|e| format!("error: cannot read {}: {e}", path.display()))?;
    compile_str(&source, opts).map_err(|d| d.render(&path.display().to_string(), &source))
}

/// Stack of the thread the phases run on. Resolve, check and lower recurse over expression
/// trees, which the parser bounds to `front::expr::MAX_TREE_DEPTH` levels; an unoptimised
/// build takes about 13 KB of stack per level, more than a test thread's 2 MB holds at 256
/// levels, so the phases get a stack segment of their own (`stacker`) with a wide margin when
/// the caller's thread has less than that left.
const PHASE_STACK: usize = 64 << 20;
/// The stack the phases need at the depth limit, with a margin: 256 levels at ~13 KB
/// (unoptimised) is 3.3 MB.
const PHASE_RED_ZONE: usize = 4 << 20;

fn run(source: &str, opts: &CompileOptions, until: Until) -> Outcome {
    // Only where less than `PHASE_RED_ZONE` is left (a test thread, a caller's small
    // thread) do the phases move to a fresh segment of `PHASE_STACK`; on a main thread the
    // check costs nothing measurable (a thread of its own per compilation cost ~0.1 ms).
    stacker::maybe_grow(PHASE_RED_ZONE, PHASE_STACK, || run_phases(source, opts, until))
}

fn run_phases(source: &str, opts: &CompileOptions, until: Until) -> Outcome {
    let mut dump = None;
    let mut phases = Vec::new();
    // the end of phase `p`: recorded, and its dump made where it was asked for
    let mut ended = |p: DumpPhase, text: &dyn Fn() -> String| {
        phases.push(p);
        if opts.dump_after == Some(p) {
            dump = Some(text());
        }
    };
    let result = (|| {
        let ast = front::parse::parse(source).map_err(Diagnostics::from)?;
        // the `tune:` block names params, channels and passes: checked once they are read
        tune::check(&ast).map_err(Diagnostics::from)?;
        ended(DumpPhase::Parse, &|| format!("{ast:#?}\n"));
        let sym = resolve::resolve(&ast, opts)?;
        ended(DumpPhase::Resolve, &|| resolve_dump(&sym));
        let checked = check::check(&sym)?;
        ended(DumpPhase::Check, &|| {
            let order: Vec<&str> = checked.order.iter().map(|&i| ast.passes[i].name.value.as_str()).collect();
            let mut s = format!("execution order: {}\n", order.join(" -> "));
            for (r, items) in &checked.items {
                s.push_str(&format!("resource {r}: {items:?}\n"));
            }
            s
        });
        if until == Until::Check {
            return Err(Diagnostics::default());
        }
        // the IR is final here: no later phase changes it
        let ir = lower::lower(&sym, &checked)?;
        debug_validate(ir::Program::lowered(&ir), "lower");
        ended(DumpPhase::Lower, &|| ir.to_string());
        let (analysis, warnings) = analyse::analyse(&ir, &sym, &checked)?;
        ended(DumpPhase::Analyse, &|| ir::WithAnalysis(&ir, &analysis).to_string());
        let layout = pack::pack(&ir, &analysis, &opts.limits)?;
        let program = ir::Program::new(&ir, &layout);
        debug_validate(program, "pack");
        let mut warnings = warnings;
        // a pass removed because a read goes around it: said, not only explained
        warnings.extend(pack::removed_pass_warnings(&ir, &layout, source));
        if opts.rounding {
            warnings.extend(rounding_warning(&program));
        }
        // a fixed-point table's overflow always; an f32 table's bound with the estimate
        warnings.extend(tables::warnings(&program, opts.rounding));
        ended(DumpPhase::Pack, &|| program.to_string());
        let schedules = schedule::choose(&program);
        ended(DumpPhase::Schedule, &|| schedules.dump(&program));
        let out = back::wgsl::codegen(&program, &schedules, &opts.limits, opts.split)?;
        ended(DumpPhase::Codegen, &|| {
            out.modules
                .iter()
                .map(|m| format!("// ----- {} -----\n{}", m.file, m.source))
                .collect()
        });
        let graph = emit::graph(&program, &out);
        warnings.extend(back::formats::render_target_warnings(&program, &graph, &opts.limits));
        ended(DumpPhase::Emit, &|| graph.to_ron());
        let cost = emit::Cost::of(&graph);
        let shaders = out.modules.into_iter().map(|m| (m.file, m.source)).collect();
        Ok(Compiled {
            ir,
            layout,
            schedules,
            graph,
            shaders,
            cost,
            warnings,
        })
    })();
    let result = match (result, until) {
        (Err(d), Until::Check) if d.is_empty() => Err(Diagnostics::default()),
        (r, _) => r,
    };
    Outcome { result, dump, phases }
}

/// A warning where storage rounding can move the visibility by more than
/// `rounding::WARN_ABOVE` (estimated only where a channel is stored below F32, whose
/// rounding is at most 2^-24 of a value).
fn rounding_warning(program: &ir::Program) -> Option<diag::Diagnostic> {
    let narrow = program
        .resources
        .iter()
        .flat_map(|r| &r.slots)
        .any(|s| s.precision != front::ast::Precision::F32);
    if !narrow {
        return None;
    }
    let e = rounding::estimate(program, rounding::Detail::Warn)?;
    if e.total <= rounding::WARN_ABOVE {
        return None;
    }
    let worst = e.channels.iter().max_by(|a, b| a.error.total_cmp(&b.error))?;
    let ch = &program.channels[worst.channel];
    let mut d = diag::Diagnostic::warning(
        diag::Phase::Analyse,
        format!(
            "storage rounding can move the visibility by up to {:.3} (a first-order estimate; warned above {}): channel `{}` at {} alone moves it by {:.3}",
            e.total,
            rounding::WARN_ABOVE,
            worst.name,
            worst.precision.name(),
            worst.error
        ),
    )
    .at(
        ch.precision_span,
        if ch.precision_overridden {
            "this precision (set by `--precision`)".to_string()
        } else {
            "this precision".to_string()
        },
    );
    let others: Vec<String> = e
        .channels
        .iter()
        .filter(|c| c.channel != worst.channel && c.error > 0.0)
        .map(|c| format!("`{}` at {}: {:.3}", c.name, c.precision.name(), c.error))
        .collect();
    if !others.is_empty() {
        d = d.note(format!("the other channels: {}", others.join(", ")));
    }
    Some(d.help(format!(
        "store `{}` at a wider precision: `sshc explain` gives the estimate at each precision",
        worst.name
    )))
}

/// In debug builds (every test), the IR a phase hands on must pass `ir::validate`.
fn debug_validate<S: ir::SlotView>(ir: ir::Program<S>, after: &str) {
    if cfg!(debug_assertions)
        && let Err(e) = ir::validate::validate(&ir)
    {
        panic!("internal compiler error: invalid IR after {after}: {e}");
    }
}

fn resolve_dump(sym: &resolve::Symbols) -> String {
    let mut s = String::new();
    for (n, i) in &sym.params {
        s.push_str(&format!(
            "param {n} = {} (fixed: {})\n",
            sym.values[*i].value, sym.t.params[*i].fixed
        ));
    }
    for (n, i) in &sym.channels {
        s.push_str(&format!("channel {n}: {}\n", sym.channel_precision[*i].name()));
    }
    for (n, i) in &sym.expansions {
        s.push_str(&format!("expansion {n}: {}\n", sym.expansion_precision[*i].name()));
    }
    for (n, r) in &sym.resources {
        s.push_str(&format!("resource {n} written by pass `{}`\n", sym.t.passes[r.writer].name.value));
    }
    s
}

/// Write the outputs of `sshc compile` into `dir`: WGSL files, `<name>.graph.ron`, `<name>.cost.md`.
pub fn write_outputs(c: &Compiled, dir: &Path) -> std::io::Result<Vec<std::path::PathBuf>> {
    std::fs::create_dir_all(dir)?;
    // what stands at an output's name must be a regular file: a link planted in the
    // output folder is refused, not written through (issue 48, item 15)
    let write = |p: &Path, text: &str| -> std::io::Result<()> {
        match std::fs::symlink_metadata(p) {
            Ok(m) if !m.is_file() => Err(std::io::Error::other(format!(
                "`{}` exists and is not a regular file: refusing to write through it",
                p.display()
            ))),
            _ => std::fs::write(p, text),
        }
    };
    let mut written = Vec::new();
    for (file, src) in &c.shaders {
        let p = dir.join(file);
        write(&p, src)?;
        written.push(p);
    }
    let g = dir.join(format!("{}.graph.ron", c.graph.technique));
    write(&g, &c.graph.to_ron())?;
    written.push(g);
    let cost = dir.join(format!("{}.cost.md", c.graph.technique));
    write(&cost, &c.cost.markdown(&c.graph.technique))?;
    written.push(cost);
    Ok(written)
}
