//! A loaded technique: a validated graph's shader modules and pipelines, made once and
//! immutable, shared (a cheap clone) by every light, view, cascade and set of targets that
//! runs it. The first stage a host builds from a [`graph::ValidGraph`]: nothing in it
//! depends on a scene, a size or a frame.

use crate::device::{Gpu, Result, RuntimeError};
use crate::graph::{self, PassGraph};
use crate::requirements::Requirements;
use crate::resources::Usages;
use crate::steps::{self, PassNode};
use crate::validate::validate_wgsl;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// The largest graph file the runtime reads.
pub const MAX_GRAPH_BYTES: u64 = 4 << 20;
/// The largest shader file the runtime reads.
pub const MAX_SHADER_BYTES: u64 = 16 << 20;

/// The most passes a graph may have: two timestamp queries each must fit one query set
/// (`wgpu::QUERY_SET_MAX_QUERIES`). Applied on every device, with or without timestamps.
pub const MAX_PASSES: usize = wgpu::QUERY_SET_MAX_QUERIES as usize / 2;

/// Read a UTF-8 file of at most `cap` bytes, and only a regular file (after links): a FIFO,
/// a device or anything else is refused before it is opened for reading, and the read is
/// bounded, so a file that grows past the cap is refused too.
pub fn read_capped(path: &Path, cap: u64) -> Result<String> {
    use std::io::Read;
    let err = |message: String| RuntimeError::File {
        path: path.to_path_buf(),
        message,
    };
    let meta = std::fs::metadata(path).map_err(|e| err(e.to_string()))?;
    if !meta.is_file() {
        return Err(err("is not a regular file (a FIFO, device or folder); refused".into()));
    }
    if meta.len() > cap {
        return Err(err(format!("is {} bytes, above the limit of {cap} bytes", meta.len())));
    }
    let file = std::fs::File::open(path).map_err(|e| err(e.to_string()))?;
    // Checked again on the open file: the path may have been replaced since.
    let meta = file.metadata().map_err(|e| err(e.to_string()))?;
    if !meta.is_file() {
        return Err(err("is not a regular file (a FIFO, device or folder); refused".into()));
    }
    let mut bytes = Vec::with_capacity(meta.len().min(cap) as usize);
    file.take(cap + 1).read_to_end(&mut bytes).map_err(|e| err(e.to_string()))?;
    if bytes.len() as u64 > cap {
        return Err(err(format!("is above the limit of {cap} bytes")));
    }
    String::from_utf8(bytes).map_err(|e| err(format!("is not UTF-8: {e}")))
}

/// A technique loaded on a device: its graph, one pipeline per step, the sampler its
/// steps bind. Immutable; cloning shares it.
#[derive(Clone)]
pub struct Technique(Arc<Loaded>);

struct Loaded {
    gpu: Gpu,
    graph: PassGraph,
    /// One node per step, per pass, in execution order.
    passes: Vec<PassNode>,
    /// What the graph's resources are used as (from the steps' plans).
    usages: Usages,
    sampler: wgpu::Sampler,
}

impl Technique {
    /// Load `T.graph.ron` and the shader files it names, from the graph's own folder.
    pub fn load(gpu: &Gpu, graph_path: &Path) -> Result<Technique> {
        let io = |path: &Path, e: std::io::Error| RuntimeError::File {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let text = read_capped(graph_path, MAX_GRAPH_BYTES)?;
        // A syntax error has a line and column: named with the file (file:line:column).
        let graph = PassGraph::from_ron(&text).map_err(|e| {
            if let graph::GraphError::Syntax { message, line, column } = e {
                RuntimeError::File {
                    path: format!("{}:{line}:{column}", graph_path.display()).into(),
                    message: format!("not a valid pass graph: {message}"),
                }
            } else {
                RuntimeError::Graph(e)
            }
        })?;
        let dir = graph_path.parent().unwrap_or(Path::new("."));
        let canon_dir = dir.canonicalize().map_err(|e| io(dir, e))?;
        let mut shaders = Vec::new();
        for p in &graph.passes {
            let path = dir.join(&p.shader);
            let canon = path.canonicalize().map_err(|e| io(&path, e))?;
            if !canon.starts_with(&canon_dir) {
                return Err(RuntimeError::File {
                    path,
                    message: "lies outside the graph's folder (through a link)".into(),
                });
            }
            // a file error names the path as the graph gives it, not the resolved one
            let src = read_capped(&canon, MAX_SHADER_BYTES).map_err(|e| {
                if let RuntimeError::File { message, .. } = e {
                    RuntimeError::File {
                        path: path.clone(),
                        message,
                    }
                } else {
                    e
                }
            })?;
            shaders.push((p.shader.clone(), src));
        }
        let graph = graph::ValidGraph::try_from(graph)?;
        Technique::new(gpu, graph, shaders)
    }

    /// Load a validated graph with its shader sources (as the compiler's API returns
    /// them): what this runtime cannot honour is refused, every module is validated again
    /// with naga, declared sizes are checked against the device, and the pipelines are
    /// built (or taken from the device's cache) before anything else is created.
    pub fn new(gpu: &Gpu, graph: graph::ValidGraph, shaders: Vec<(String, String)>) -> Result<Technique> {
        let graph = graph.into_inner();
        if graph.passes.is_empty() {
            return Err(RuntimeError::NotFound(format!(
                "technique `{}`: the graph has no passes; there is nothing to run",
                graph.technique
            )));
        }
        if graph.passes.len() > MAX_PASSES {
            return Err(RuntimeError::Limit {
                what: format!("technique `{}`: passes (two GPU timestamps each, one query set)", graph.technique),
                needed: graph.passes.len() as u64,
                limit: MAX_PASSES as u64,
            });
        }
        // every feature and limit the graph needs, all missing ones listed at once
        Requirements::of(&graph).check(gpu, &graph.technique)?;
        let mut sources: HashMap<String, Arc<str>> = HashMap::new();
        for p in &graph.passes {
            let src = shaders
                .iter()
                .find(|(f, _)| f == &p.shader)
                .map(|(_, s)| s.as_str())
                .ok_or_else(|| RuntimeError::NotFound(format!("pass `{}` names shader `{}`, which was not given", p.name, p.shader)))?;
            validate_wgsl(src).map_err(|message| RuntimeError::Shader {
                file: p.shader.clone(),
                message,
            })?;
            if !sources.contains_key(&p.shader) {
                let src: Arc<str> = src.into();
                gpu.module(&p.shader, &src)?;
                sources.insert(p.shader.clone(), src);
            }
        }
        for t in &graph.textures {
            if t.format.is_table() && t.mips {
                return Err(RuntimeError::NotFound(format!(
                    "texture `{}`: a summed-area table has no mip levels",
                    t.name
                )));
            }
        }
        // Params: the uniform must fit the device, and every field must lie inside it.
        let max_uniform = gpu.limits.max_uniform_buffer_binding_size;
        if graph.params_size as u64 > max_uniform || !graph.params_size.is_multiple_of(4) {
            return Err(RuntimeError::Limit {
                what: "the Params uniform (bytes, a multiple of 4)".into(),
                needed: graph.params_size as u64,
                limit: max_uniform,
            });
        }
        for p in &graph.params {
            if let Some(off) = p.offset
                && (!off.is_multiple_of(4) || off as u64 + 4 > graph.params_size as u64)
            {
                return Err(RuntimeError::Param(format!(
                    "param `{}` lies at byte {off}, outside the {}-byte Params uniform",
                    p.name, graph.params_size
                )));
            }
        }
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("sshc linear clamp"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            address_mode_w: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let passes = steps::build(gpu, &graph, &sources)?;
        Ok(Technique(Arc::new(Loaded {
            gpu: gpu.clone(),
            usages: Usages::of(&graph),
            graph,
            passes,
            sampler,
        })))
    }

    /// The technique's graph (validated when it was loaded).
    pub fn graph(&self) -> &PassGraph {
        &self.0.graph
    }

    /// The device it was loaded on (a handle: the device, queue and caches are shared).
    pub fn gpu(&self) -> &Gpu {
        &self.0.gpu
    }

    pub(crate) fn passes(&self) -> &[PassNode] {
        &self.0.passes
    }

    pub(crate) fn usages(&self) -> &Usages {
        &self.0.usages
    }

    /// Whether it classifies silhouettes (a Geometry pass): a scene it runs on must be
    /// uploaded with edge adjacency (`Scene::upload` with it among the techniques).
    pub fn needs_edge_adjacency(&self) -> bool {
        self.0.usages.edges
    }

    pub(crate) fn sampler(&self) -> &wgpu::Sampler {
        &self.0.sampler
    }
}

impl Technique {
    /// Whether `other` is this loaded technique (a clone of it), not another load.
    pub fn same(&self, other: &Technique) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }

    /// What the technique needs of a device ([`Requirements::of`]).
    pub fn requirements(&self) -> Requirements {
        Requirements::of(self.graph())
    }
}

impl std::fmt::Debug for Technique {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Technique")
            .field("name", &self.graph().technique)
            .finish_non_exhaustive()
    }
}

impl PartialEq for Technique {
    /// The same load (not merely an equal graph: pipelines are per load).
    fn eq(&self, other: &Technique) -> bool {
        self.same(other)
    }
}
