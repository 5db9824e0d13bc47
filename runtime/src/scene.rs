//! Stage 3 of the runtime: the scene's geometry on the GPU ([`Scene`]), uploaded once and
//! shared by every technique's [`crate::gpu::Targets`] made on it. Its meshes, instances
//! and edge adjacency do not depend on a camera, a light or a size: a window resize or a new
//! light never uploads them again.

use crate::adjacency::{Adjacency, AdjacencyCounts};
use crate::device::{Gpu, Result, RuntimeError};
use crate::fit::Boxes;
use crate::frame::SceneInputs;
use crate::geometry::{Geometry, GeometryBuffers};
use crate::resources::DEFAULT_MAX_BYTES;
use crate::technique::Technique;
use std::sync::atomic::{AtomicU64, Ordering};

/// Each upload's identity: targets remember the scene they were made on.
static NEXT_SCENE: AtomicU64 = AtomicU64::new(1);

/// A host's geometry on the GPU: its meshes (uploaded once), its instances with their
/// transforms (moved in place: [`Scene::set_transforms`]) and, when a technique it serves
/// classifies silhouettes, each mesh's edge adjacency (built once, in object space).
pub struct Scene {
    gpu: Gpu,
    buffers: GeometryBuffers,
    id: u64,
    /// The casting instances' bounding box under the current transforms (world space).
    caster_bounds: Option<[[f32; 3]; 2]>,
    /// The placed triangles as a soup, with the casting vertices' count, kept when a
    /// technique it serves was specialised for a scene: the exact check of its depth floor.
    soup: Option<(Vec<f32>, Option<u32>)>,
}

impl Scene {
    /// Upload `geometry` for `techniques` (the ones that will run on it: the edge adjacency
    /// is built when one of them classifies silhouettes), within [`DEFAULT_MAX_BYTES`].
    pub fn upload(gpu: &Gpu, geometry: &Geometry, techniques: &[&Technique]) -> Result<Scene> {
        Scene::upload_within(gpu, geometry, techniques, DEFAULT_MAX_BYTES)
    }

    /// [`Scene::upload`], refused when the edge adjacency could take more than `max_bytes`
    /// (bounded from the casting triangles before it is built: [`Adjacency::max_bytes`]).
    pub fn upload_within(gpu: &Gpu, geometry: &Geometry, techniques: &[&Technique], max_bytes: u64) -> Result<Scene> {
        Scene::build(gpu, geometry, techniques, max_bytes, || geometry.soup().map(|(v, c)| (v, Some(c))))
    }

    /// The upload; `soup` gives the placed casters for a specialised technique's exact
    /// depth-floor check, asked only when one of `techniques` is specialised.
    fn build(
        gpu: &Gpu,
        geometry: &Geometry,
        techniques: &[&Technique],
        max_bytes: u64,
        soup: impl FnOnce() -> Result<(Vec<f32>, Option<u32>)>,
    ) -> Result<Scene> {
        let edges = techniques.iter().any(|t| t.usages().edges);
        if edges {
            let tris = geometry.casting_triangles();
            let needed = Adjacency::max_bytes(tris);
            if needed > max_bytes {
                return Err(RuntimeError::Limit {
                    what: format!("edge adjacency of {tris} casting triangles (bytes)"),
                    needed,
                    limit: max_bytes,
                });
            }
        }
        let buffers = GeometryBuffers::new(gpu, geometry, edges)?;
        let caster_bounds = buffers.caster_bounds_at(&buffers.transforms);
        // a specialised technique's depth floor is checked on the placed triangles
        let soup = match techniques.iter().any(|t| t.graph().specialised.is_some()) {
            true => Some(soup()?),
            false => None,
        };
        Ok(Scene {
            gpu: gpu.clone(),
            buffers,
            id: NEXT_SCENE.fetch_add(1, Ordering::Relaxed),
            caster_bounds,
            soup,
        })
    }

    /// Upload a triangle soup (world-space position and normal per vertex, three vertices a
    /// triangle) as one world-space instance per object ([`Geometry::from_soup`], which says
    /// what it refuses).
    pub fn from_soup(
        gpu: &Gpu,
        vertices: &[f32],
        meshes: &[std::ops::Range<u32>],
        casting_vertices: Option<u32>,
        unshadowed: &[std::ops::Range<u32>],
        techniques: &[&Technique],
        max_bytes: u64,
    ) -> Result<Scene> {
        let geometry = Geometry::from_soup(vertices, meshes, casting_vertices, unshadowed)?;
        // the soup as given: not made again from the geometry
        Scene::build(gpu, &geometry, techniques, max_bytes, || Ok((vertices.to_vec(), casting_vertices)))
    }

    /// [`Scene::from_soup`] of a [`SceneInputs`]' soup, within [`DEFAULT_MAX_BYTES`].
    pub fn from_inputs(gpu: &Gpu, s: &SceneInputs, techniques: &[&Technique]) -> Result<Scene> {
        Scene::from_soup(
            gpu,
            &s.vertices,
            &s.meshes,
            s.casting_vertices,
            &s.unshadowed,
            techniques,
            DEFAULT_MAX_BYTES,
        )
    }

    /// Set every instance's transform (column-major, one per instance, each finite, affine
    /// and invertible; an instance that does not move keeps its own): the placement records
    /// are written through the queue and the next prepared frame places the instances
    /// again. Nothing is created or allocated. Refused, with nothing changed, as
    /// [`Geometry`] refuses a transform.
    pub fn set_transforms(&mut self, transforms: &[[f32; 16]]) -> Result<()> {
        self.buffers.check_transforms(transforms)?;
        self.caster_bounds = self.buffers.caster_bounds_at(transforms);
        self.buffers.write_transforms(&self.gpu.queue, transforms);
        Ok(())
    }

    /// The instances' world-space boxes under the current transforms: what a light is
    /// fitted to ([`crate::gpu::LightInputs::fit`]).
    pub fn boxes(&self) -> &Boxes {
        self.buffers.boxes()
    }

    /// The casting instances' bounding box under the current transforms.
    pub fn caster_bounds(&self) -> Option<[[f32; 3]; 2]> {
        self.caster_bounds
    }

    /// The edge adjacency built for silhouettes (`None` when no technique needed it).
    pub fn edge_counts(&self) -> Option<AdjacencyCounts> {
        self.buffers.scene.edges.as_ref().map(|e| e.counts)
    }

    /// Whether the edge adjacency was built (a technique with Geometry passes needs it).
    pub fn has_edges(&self) -> bool {
        self.buffers.scene.edges.is_some()
    }

    /// The device the scene lives on.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    pub(crate) fn id(&self) -> u64 {
        self.id
    }

    pub(crate) fn buffers(&self) -> &GeometryBuffers {
        &self.buffers
    }

    pub(crate) fn buffers_mut(&mut self) -> &mut GeometryBuffers {
        &mut self.buffers
    }

    pub(crate) fn soup(&self) -> Option<(&[f32], Option<u32>)> {
        self.soup.as_ref().map(|(v, c)| (v.as_slice(), *c))
    }
}
