//! Stage 3 of the runtime: the scene's geometry on the GPU ([`Scene`]), uploaded once and
//! shared by every technique's [`crate::gpu::Targets`] made on it. Its meshes, instances
//! and edge adjacency do not depend on a camera, a light or a size: a window resize or a new
//! light never uploads them again.

use crate::adjacency::{Adjacency, AdjacencyCounts};
use crate::device::{Gpu, Result, RuntimeError};
use crate::fit::Boxes;
use crate::frame::SceneInputs;
use crate::geometry::{Changes, Geometry, GeometryBuffers, Instance, Mesh};
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

    /// Upload one more mesh and return its index, for [`Scene::add_instance`]: its bytes
    /// only (its vertices, its indices unless listed out and, when a technique the scene
    /// serves classifies silhouettes, its edge adjacency, built here); nothing else is
    /// uploaded again. The scene's buffers keep room to grow (at least twofold when one
    /// is full), so most changes make no buffer. Refused, with nothing changed, as
    /// [`Geometry`] refuses a mesh, and for a scene kept for a specialised technique.
    ///
    /// The targets made on the scene take the change with [`crate::gpu::Targets::set_scene`]
    /// (their next frame refuses the scene until then).
    pub fn add_mesh(&mut self, mesh: &Mesh) -> Result<usize> {
        self.changeable()?;
        let gpu = self.gpu.clone();
        gpu.scoped("adding a mesh to the scene", || self.buffers.add_mesh(&gpu, mesh))?
    }

    /// Add an instance after the others (draw order) and return its index, its place in
    /// [`Scene::set_transforms`]: its placement record is written and the next frame
    /// places it on the GPU (an instance added later is placed there even when it does not
    /// move; in world space it is drawn from its mesh). Refused, with nothing changed, as
    /// [`Geometry`] refuses an instance, for a mesh the scene does not hold, and (a scene
    /// with edge adjacency) for a casting instance of a mesh uploaded with no instance that
    /// casts and moves: add that mesh again.
    pub fn add_instance(&mut self, instance: &Instance) -> Result<usize> {
        self.changeable()?;
        let gpu = self.gpu.clone();
        let i = gpu.scoped("adding an instance to the scene", || self.buffers.add_instance(&gpu, instance))??;
        self.caster_bounds = self.buffers.caster_bounds_at(&self.buffers.transforms);
        Ok(i)
    }

    /// Remove instance `index`; those after it move down one place (draw order is kept).
    pub fn remove_instance(&mut self, index: usize) -> Result<()> {
        self.changeable()?;
        let gpu = self.gpu.clone();
        gpu.scoped("removing an instance from the scene", || self.buffers.remove_instance(&gpu, index))??;
        self.caster_bounds = self.buffers.caster_bounds_at(&self.buffers.transforms);
        Ok(())
    }

    /// Remove mesh `index` (the other meshes keep their indices); refused while an instance
    /// places it.
    pub fn remove_mesh(&mut self, index: usize) -> Result<()> {
        self.changeable()?;
        let gpu = self.gpu.clone();
        gpu.scoped("removing a mesh from the scene", || self.buffers.remove_mesh(&gpu, index))?
    }

    /// The meshes the scene holds (removed ones excluded).
    pub fn mesh_count(&self) -> usize {
        self.buffers.mesh_count()
    }

    /// The instances, in draw order.
    pub fn instance_count(&self) -> usize {
        self.buffers.instance_count()
    }

    /// Bytes the changes since the upload wrote to the GPU ([`Scene::add_mesh`],
    /// [`Scene::add_instance`]; not the transforms): what a change cost.
    pub fn bytes_added(&self) -> u64 {
        self.buffers.changes.uploaded
    }

    /// Times one of the scene's buffers was made again to grow since the upload (each
    /// holds twice what it then held): a change that grew none made no buffer, and the
    /// targets take it without binding anything again.
    pub fn buffers_grown(&self) -> u64 {
        self.buffers.changes.grown
    }

    /// A scene kept for a specialised technique keeps its triangles for the exact check of
    /// its depth floor: it is not changed in place.
    fn changeable(&self) -> Result<()> {
        match self.soup {
            Some(_) => Err(RuntimeError::Param(
                "this scene was uploaded for a technique specialised for a scene, which keeps its triangles to check its depth floor: upload the changed geometry instead (`Scene::upload`)".into(),
            )),
            None => Ok(()),
        }
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

    pub(crate) fn changes(&self) -> Changes {
        self.buffers.changes
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
