//! Reading a pass graph and refusing what the runtime cannot trust: versions, paths,
//! references, params, layers, samples and formats.

use crate::schema::{
    BufferDecl, Draw, Extent, GraphError, MAX_RECORD_BYTES, MAX_VERTICES_PER_RECORD, PassGraph, SCHEMA_VERSION, TextureDecl, View,
};
use crate::uniforms::MAX_LIGHT_SAMPLES;
use serde::Deserialize;

/// A pass graph that passed every check the runtime relies on ([`PassGraph::from_ron`]'s,
/// made on the value: no text round trip), the only kind `sshc_runtime::gpu::Technique::new`
/// takes a graph as (issue 49's first stage). Read it through `Deref`; take it apart with
/// [`ValidGraph::into_inner`].
#[derive(Clone, Debug, PartialEq)]
pub struct ValidGraph(PassGraph);

impl TryFrom<PassGraph> for ValidGraph {
    type Error = GraphError;

    /// The checks of [`PassGraph::from_ron`] after its parse: the schema version, params,
    /// unique names, buffers, samples, the shadow-map size, textures and their channels,
    /// shader paths, references, the passes' order and the scene facts.
    fn try_from(g: PassGraph) -> Result<ValidGraph, GraphError> {
        g.validated().map(ValidGraph)
    }
}

impl ValidGraph {
    /// The graph, no longer known to be valid once changed.
    pub fn into_inner(self) -> PassGraph {
        self.0
    }
}

impl std::ops::Deref for ValidGraph {
    type Target = PassGraph;
    fn deref(&self) -> &PassGraph {
        &self.0
    }
}

impl PassGraph {
    /// Whether the technique is written for a light of `kind`: its `light:` list (`lights`)
    /// is empty, `Any`, or names the kind. The one reading of the list the runtime's
    /// refusal and the lab's choice to run a pair anyway share.
    pub fn written_for(&self, kind: crate::LightKind) -> bool {
        self.lights.is_empty() || self.lights.iter().any(|m| m.accepts(kind))
    }

    /// The `Params` uniform with every runtime param at its default value (`params_size`
    /// bytes, each param at its offset, padding zero): what the targets write first.
    pub fn default_params(&self) -> Vec<u8> {
        let mut bytes = vec![0u8; self.params_size as usize];
        for p in &self.params {
            if let Some(off) = p.offset {
                let o = off as usize;
                if o + 4 <= bytes.len() {
                    bytes[o..o + 4].copy_from_slice(&p.ty.bytes(p.value));
                }
            }
        }
        bytes
    }

    /// Serialise as pretty RON.
    pub fn to_ron(&self) -> String {
        let config = ron::ser::PrettyConfig::new().depth_limit(8).indentor("  ".to_string());
        ron::ser::to_string_pretty(self, config).unwrap_or_else(|e| format!("// serialisation failed: {e}"))
    }

    /// Parse and check a graph: schema version, shader paths that stay inside the graph's
    /// folder, and texture names that resolve. Shader validation and device limits are
    /// checked by the runtime when it loads the modules.
    pub fn from_ron(text: &str) -> Result<PassGraph, GraphError> {
        // Read the version first, so that an old graph gets the version error, not a schema one.
        #[derive(Deserialize)]
        struct Versioned {
            version: u32,
        }
        let syntax = |e: ron::error::SpannedError| GraphError::Syntax {
            message: e.code.to_string(),
            line: e.span.start.line,
            column: e.span.start.col,
        };
        if let Ok(v) = ron::from_str::<ron::Value>(text)
            && let Ok(v) = v.into_rust::<Versioned>()
            && v.version != SCHEMA_VERSION
        {
            return Err(GraphError::Version {
                found: v.version,
                expected: SCHEMA_VERSION,
            });
        }
        let g: PassGraph = ron::from_str(text).map_err(syntax)?;
        ValidGraph::try_from(g).map(ValidGraph::into_inner)
    }

    /// Every check of [`PassGraph::from_ron`] on a graph already in memory (what the
    /// compiler returns): the body of [`ValidGraph::try_from`].
    fn validated(self) -> Result<PassGraph, GraphError> {
        let g = self;
        if g.version != SCHEMA_VERSION {
            return Err(GraphError::Version {
                found: g.version,
                expected: SCHEMA_VERSION,
            });
        }
        g.check_params()?;
        check_unique("texture", g.textures.iter().map(|t| &t.name))?;
        check_unique("pass", g.passes.iter().map(|p| &p.name))?;
        check_unique("param", g.params.iter().map(|p| &p.name))?;
        check_unique("buffer", g.buffers.iter().map(|b| &b.name))?;
        g.check_buffers()?;
        if g.samples == 0 || g.samples > MAX_LIGHT_SAMPLES {
            return Err(GraphError::Samples(format!(
                "samples {} is outside 1..={MAX_LIGHT_SAMPLES}",
                g.samples
            )));
        }
        if let Some(n) = g.shadow_map
            && !(1..=crate::MAX_SHADOW_MAP).contains(&n)
        {
            return Err(GraphError::ShadowMap(n));
        }
        for t in &g.textures {
            if t.views != 1 && t.views != g.samples {
                return Err(GraphError::Texture {
                    texture: t.name.clone(),
                    field: "views",
                    message: format!("{} views; a texture holds 1 or the graph's {} samples", t.views, g.samples),
                });
            }
            if t.extent == Extent::Camera && (t.layers != 1 || t.mips || t.views != 1) {
                return Err(GraphError::Texture {
                    texture: t.name.clone(),
                    field: "extent",
                    message: "a camera-sized texture has one layer, one view and no mip chain".into(),
                });
            }
            if t.layers == 0 {
                return Err(GraphError::Texture {
                    texture: t.name.clone(),
                    field: "layers",
                    message: "0 layers; a texture has at least 1".into(),
                });
            }
            // The channel table describes the storage (decoding, dumps): finite numbers,
            // places inside the texture.
            for c in &t.channels {
                let bad = |field: &'static str, message: String| GraphError::Texture {
                    texture: t.name.clone(),
                    field,
                    message: format!("channel `{}`: {message}", c.name),
                };
                if !(c.bias.is_finite() && c.scale.is_finite() && c.scale != 0.0) {
                    return Err(bad(
                        "channels",
                        format!("bias {} and scale {} must be finite, the scale non-zero", c.bias, c.scale),
                    ));
                }
                if !(c.range.0.is_finite() && c.range.1.is_finite() && c.range.0 <= c.range.1) {
                    return Err(bad(
                        "channels",
                        format!("range ({}, {}) must be finite and ordered", c.range.0, c.range.1),
                    ));
                }
                if c.layer >= t.layers || c.component > 3 {
                    return Err(bad(
                        "channels",
                        format!(
                            "layer {} component {} lies outside the texture's {} layer(s) of 4 components",
                            c.layer, c.component, t.layers
                        ),
                    ));
                }
            }
        }
        for p in &g.passes {
            if !is_plain_file_name(&p.shader) {
                return Err(GraphError::Path {
                    pass: p.name.clone(),
                    path: p.shader.clone(),
                });
            }
            let per_sample = p.views.is_per_sample();
            for s in &p.steps {
                for w in &s.writes {
                    let views = g.texture(&w.texture).map_or(1, |t| t.views);
                    if per_sample && views != g.samples || !per_sample && views != 1 {
                        return Err(GraphError::Samples(format!(
                            "pass `{}` ({:?}) writes texture `{}` of {views} view(s)",
                            p.name, p.views, w.texture
                        )));
                    }
                }
                if s.draw.joins_sample_views() && !per_sample {
                    return Err(GraphError::Samples(format!(
                        "pass `{}` finds discontinuities between sample views, but renders the light's centre only",
                        p.name
                    )));
                }
                let names = s.reads.iter().map(|b| &b.texture).chain(s.writes.iter().map(|t| &t.texture));
                for n in names {
                    if !g.textures.iter().any(|t| &t.name == n) {
                        return Err(GraphError::Reference {
                            pass: p.name.clone(),
                            name: n.clone(),
                        });
                    }
                }
            }
        }
        g.check_order()?;
        if let Some(f) = g.specialised.as_ref().and_then(|s| s.depth_floor)
            && !(0.0..=1.0).contains(&f)
        {
            return Err(GraphError::Facts(format!("`depth_floor` {f} is not a normalised depth in [0, 1]")));
        }
        Ok(g)
    }

    /// Every param value and range finite, and every value within its range.
    fn check_params(&self) -> Result<(), GraphError> {
        for p in &self.params {
            let bad = |message: String| {
                Err(GraphError::Param {
                    param: p.name.clone(),
                    message,
                })
            };
            if !p.value.is_finite() {
                return bad(format!("value {} is not a finite number", p.value));
            }
            if let Some((lo, hi)) = p.range {
                if !lo.is_finite() || !hi.is_finite() || lo > hi {
                    return bad(format!("range [{lo}, {hi}] is not a finite interval"));
                }
                if !(lo..=hi).contains(&p.value) {
                    return bad(format!("value {} lies outside its range [{lo}, {hi}]", p.value));
                }
            }
        }
        Ok(())
    }

    /// Every texture a step reads is written by an earlier step (of an earlier pass, or
    /// earlier in the same pass; a mip chain's step reads the levels of the texture it
    /// writes), and every written layer lies within its texture.
    fn check_order(&self) -> Result<(), GraphError> {
        let mut written: Vec<&str> = Vec::new();
        for p in &self.passes {
            for s in &p.steps {
                // a dispatch names a compute entry and nothing else; a draw a vertex and a
                // fragment entry and no compute entry
                let dispatch = s.draw.is_dispatch();
                let fits = if dispatch {
                    s.compute.is_some() && s.vertex.is_none() && s.fragment.is_none()
                } else {
                    s.compute.is_none() && s.vertex.is_some() && s.fragment.is_some()
                };
                if !fits {
                    return Err(GraphError::Step {
                        pass: p.name.clone(),
                        message: format!(
                            "a {:?} step needs {}",
                            s.draw,
                            if dispatch {
                                "a compute entry point and no vertex or fragment entry"
                            } else {
                                "vertex and fragment entry points and no compute entry"
                            }
                        ),
                    });
                }
                // a deferred Shade: the G-buffer, then the pixels that read it
                if s.draw.is_deferred_shade() && !p.kind.is_shade() {
                    return Err(GraphError::Step {
                        pass: p.name.clone(),
                        message: format!("a {:?} step belongs to a Shade pass, not a {:?} pass", s.draw, p.kind),
                    });
                }
                if s.draw.reads_gbuffer() && !p.steps.iter().take_while(|t| !std::ptr::eq(*t, s)).any(|t| t.draw.writes_gbuffer()) {
                    return Err(GraphError::Step {
                        pass: p.name.clone(),
                        message: "a ComputePixels step reads the G-buffer, which no earlier CameraGBuffer step of its pass writes".into(),
                    });
                }
                for b in &s.reads {
                    let same_step = b.view == View::PreviousLevel && s.writes.iter().any(|w| w.texture == b.texture);
                    if !same_step && !written.contains(&b.texture.as_str()) {
                        return Err(GraphError::Unwritten {
                            pass: p.name.clone(),
                            texture: b.texture.clone(),
                        });
                    }
                }
                // camera-sized textures: a Shade's debug outputs, written by its camera
                // steps (after the camera outputs), one layer, no mip chain, read by no pass
                for w in &s.writes {
                    if let Some(t) = self.texture(&w.texture)
                        && (t.extent == Extent::Camera) != s.draw.writes_camera_textures()
                    {
                        return Err(GraphError::Step {
                            pass: p.name.clone(),
                            message: format!(
                                "a {:?} step writes texture `{}` of extent {:?}: camera-sized textures are written by a Shade's SceneFromCamera or ComputePixels step, and only they",
                                s.draw, t.name, t.extent
                            ),
                        });
                    }
                }
                if let Some(b) = s
                    .reads
                    .iter()
                    .find(|b| self.texture(&b.texture).is_some_and(|t| t.extent == Extent::Camera))
                {
                    return Err(GraphError::Step {
                        pass: p.name.clone(),
                        message: format!(
                            "a step reads camera-sized texture `{}`: no pass reads a Shade's debug outputs",
                            b.texture
                        ),
                    });
                }
                for w in &s.writes {
                    if (s.draw.stores_textures() || s.draw.writes_camera_textures() && s.draw.is_dispatch())
                        && let Some(t) = self.texture(&w.texture)
                        && !t.format.storable()
                    {
                        return Err(GraphError::Texture {
                            texture: w.texture.clone(),
                            field: "format",
                            message: format!(
                                "pass `{}` writes it from a compute step, but {:?} is not a storage format",
                                p.name, t.format
                            ),
                        });
                    }
                    let layers = self.texture(&w.texture).map_or(0, |t| t.layers);
                    if w.layer >= layers {
                        return Err(GraphError::Layer {
                            pass: p.name.clone(),
                            texture: w.texture.clone(),
                            layer: w.layer,
                            layers,
                        });
                    }
                    written.push(&w.texture);
                }
            }
        }
        Ok(())
    }

    pub fn texture(&self, name: &str) -> Option<&TextureDecl> {
        self.textures.iter().find(|t| t.name == name)
    }

    pub fn buffer(&self, name: &str) -> Option<&BufferDecl> {
        self.buffers.iter().find(|b| b.name == name)
    }

    /// Every generated buffer well formed, every step naming a declared one, and drawn
    /// only after a `Silhouettes` step wrote it.
    fn check_buffers(&self) -> Result<(), GraphError> {
        for b in &self.buffers {
            let bad = |message: String| {
                Err(GraphError::Buffer {
                    buffer: b.name.clone(),
                    message,
                })
            };
            if b.record_bytes == 0 || b.record_bytes % 16 != 0 || b.record_bytes > MAX_RECORD_BYTES {
                return bad(format!(
                    "record_bytes {} is not a multiple of 16 in 16..={MAX_RECORD_BYTES}",
                    b.record_bytes
                ));
            }
            if b.vertices_per_record == 0 || b.vertices_per_record > MAX_VERTICES_PER_RECORD {
                return bad(format!(
                    "vertices_per_record {} is outside 1..={MAX_VERTICES_PER_RECORD}",
                    b.vertices_per_record
                ));
            }
        }
        let mut written: Vec<&str> = Vec::new();
        for p in &self.passes {
            for s in &p.steps {
                let (name, writes) = match &s.draw {
                    Draw::Silhouettes { buffer } | Draw::Discontinuities { buffer, .. } => (buffer, true),
                    Draw::Primitives { buffer, .. } => (buffer, false),
                    Draw::SceneFromLight
                    | Draw::SceneFromCamera
                    | Draw::CameraGBuffer
                    | Draw::FullScreen
                    | Draw::MipLevels
                    | Draw::ComputeRows
                    | Draw::ComputeColumns
                    | Draw::ComputeTexels
                    | Draw::ComputePixels
                    | Draw::ComputeMipLevels => continue,
                };
                let bad = |message: String| {
                    Err(GraphError::Buffer {
                        buffer: name.clone(),
                        message,
                    })
                };
                if self.buffer(name).is_none() {
                    return bad(format!("pass `{}` names it, but the graph does not declare it", p.name));
                }
                if writes {
                    written.push(name);
                } else if !written.contains(&name.as_str()) {
                    return bad(format!("pass `{}` draws it, but no earlier Silhouettes step writes it", p.name));
                }
            }
        }
        Ok(())
    }
}

fn check_unique<'a>(what: &'static str, names: impl Iterator<Item = &'a String>) -> Result<(), GraphError> {
    let mut seen = std::collections::HashSet::new();
    for n in names {
        if !seen.insert(n.as_str()) {
            return Err(GraphError::Duplicate { what, name: n.clone() });
        }
    }
    Ok(())
}

/// A file name with no directory part, no `..`, not absolute.
pub fn is_plain_file_name(p: &str) -> bool {
    !p.is_empty() && !p.contains(['/', '\\', ':']) && p != "." && p != ".." && !p.starts_with('.')
}
