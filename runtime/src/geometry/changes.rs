//! A scene changed in place: a mesh or an instance added or removed after the upload,
//! without uploading or binding the rest again ([`crate::gpu::Scene::add_mesh`] and the
//! calls beside it).
//!
//! Every buffer of the scene is a [`Pool`]: what is added takes a free range (growing the
//! buffer, at least twofold, when none is left), what is removed hands its ranges back.
//! A mesh added uploads its own bytes only (vertices, indices, and its edge adjacency when
//! the scene classifies silhouettes); an instance added writes its placement record only,
//! and the placement step places it on the GPU in the next frame (an instance added later
//! is placed there even when it does not move; one in world space is drawn from its mesh
//! and only its edges are placed, under the identity, exactly). The draws are made again
//! on the CPU, in draw order. Removed instances' placed edges are zeroed: an edge of no
//! face is never a silhouette, so the classification runs over the holes unchanged.
//!
//! What the targets made on the scene take again ([`Changes`]): the draws, recorded again
//! into their bundles; and, only when a buffer grew or the edges changed, the bindings of
//! the steps that bind the scene.

use super::*;
use std::ops::Range;

/// Which of a scene's [`Pools`].
#[derive(Clone, Copy)]
enum Which {
    Meshes,
    Indices,
    MeshEdges,
    MeshPlanes,
    MeshFaces,
    Placed,
    Edges,
    Planes,
    Faces,
    Claims,
    Records,
}

impl Pools {
    fn get(&mut self, w: Which) -> &mut Pool {
        match w {
            Which::Meshes => &mut self.meshes,
            Which::Indices => &mut self.indices,
            Which::MeshEdges => &mut self.mesh_edges,
            Which::MeshPlanes => &mut self.mesh_planes,
            Which::MeshFaces => &mut self.mesh_faces,
            Which::Placed => &mut self.placed,
            Which::Edges => &mut self.edges,
            Which::Planes => &mut self.planes,
            Which::Faces => &mut self.faces,
            Which::Claims => &mut self.claims,
            Which::Records => &mut self.records,
        }
    }

    /// A range of each (`n` 0 takes nothing: an empty range), all or none: a refusal hands
    /// back what was taken. Each range's end fits the `u32` the spans and draws hold.
    fn take(&mut self, gpu: &Gpu, wants: &[(Which, u64)]) -> Result<Vec<Range<u32>>> {
        let mut got: Vec<Range<u64>> = Vec::with_capacity(wants.len());
        for &(w, n) in wants {
            let r = if n == 0 {
                Ok(0..0)
            } else {
                self.get(w).alloc(gpu, n).and_then(|r| match u32::try_from(r.end) {
                    Ok(_) => Ok(r),
                    Err(_) => Err(RuntimeError::Limit {
                        what: "elements of one of the scene's buffers (its spans are u32)".into(),
                        needed: r.end,
                        limit: u32::MAX.into(),
                    }),
                })
            };
            match r {
                Ok(r) => got.push(r),
                Err(e) => {
                    for (&(w, _), r) in wants.iter().zip(got) {
                        self.get(w).free(r);
                    }
                    return Err(e);
                }
            }
        }
        Ok(got.into_iter().map(|r| r.start as u32..r.end as u32).collect())
    }

    fn give_back(&mut self, w: Which, first: u32, n: u32) {
        self.get(w).free(u64::from(first)..u64::from(first) + u64::from(n));
    }
}

impl GeometryBuffers {
    /// Upload one more mesh (checked as [`Geometry::check`] checks one): its vertices where
    /// the placement step reads them, its indices (none when listed out) and, when the scene
    /// classifies silhouettes, its edge adjacency. Returns its index.
    pub fn add_mesh(&mut self, gpu: &Gpu, mesh: &Mesh) -> Result<usize> {
        let index = self.meshes.len();
        check_mesh(index, mesh)?;
        let listed = mesh.listed_out();
        let adjacency = self.edges_on.then(|| adjacency_of(mesh));
        let lens = adjacency
            .as_ref()
            .map_or([0; 3], |a| [a.edges.len(), a.planes.len(), a.edge_faces.len()].map(|n| n as u64));
        let r = self.pools.take(
            gpu,
            &[
                (Which::Meshes, mesh.positions.len() as u64),
                (Which::Indices, if listed { 0 } else { mesh.indices.len() as u64 }),
                (Which::MeshEdges, lens[0]),
                (Which::MeshPlanes, lens[1]),
                (Which::MeshFaces, lens[2]),
            ],
        )?;
        let mut vertices = Vec::with_capacity(mesh.positions.len() * 24);
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            vertices.extend(p.iter().chain(n).flat_map(|c| c.to_le_bytes()));
        }
        let mut writes = vec![(Which::Meshes, r[0].start, vertices)];
        if !listed {
            writes.push((
                Which::Indices,
                r[1].start,
                mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect(),
            ));
        }
        if let Some(a) = &adjacency {
            writes.push((Which::MeshEdges, r[2].start, a.edges.iter().flat_map(|e| e.to_bytes()).collect()));
            writes.push((
                Which::MeshPlanes,
                r[3].start,
                a.planes.iter().flatten().flat_map(|x| x.to_le_bytes()).collect(),
            ));
            writes.push((
                Which::MeshFaces,
                r[4].start,
                a.edge_faces.iter().flat_map(|f| f.to_le_bytes()).collect(),
            ));
        }
        for (w, at, bytes) in writes {
            self.write(gpu, w, at, &bytes);
        }
        self.meshes.push(Some(MeshSlot {
            vertices: mesh.positions.len() as u32,
            elements: mesh.indices.len() as u32,
            first_index: (!listed).then_some(r[1].start),
            at: [Some(r[0].start), None],
            edges: adjacency.as_ref().map(|a| EdgeSpan::of(a, [r[2].start, r[3].start, r[4].start, 0])),
            bbox: box_of(mesh.positions.iter().copied()),
        }));
        self.changed(gpu, false);
        Ok(index)
    }

    /// Add an instance after the others (draw order): its placement record written, placed
    /// on the GPU in the next frame. Returns its index (its place in
    /// [`crate::gpu::Scene::set_transforms`]). Refused, with nothing changed, for a mesh the
    /// scene does not hold, a transform [`Geometry`] refuses, more than [`MAX_INSTANCES`],
    /// and (a scene that classifies silhouettes) a casting instance of a mesh uploaded with
    /// no instance that casts and moves, whose adjacency was not kept.
    pub fn add_instance(&mut self, gpu: &Gpu, inst: &Instance) -> Result<usize> {
        let index = self.slots.len();
        let name = || match inst.name.is_empty() {
            true => format!("instance {index}"),
            false => format!("instance {index} (`{}`)", inst.name),
        };
        if index >= MAX_INSTANCES {
            return Err(RuntimeError::Limit {
                what: "instances of one geometry".into(),
                needed: index as u64 + 1,
                limit: MAX_INSTANCES as u64,
            });
        }
        check_transform(&inst.transform, name)?;
        let Some(Some(m)) = self.meshes.get(inst.mesh).cloned() else {
            return Err(RuntimeError::Param(format!(
                "{} places mesh {}, which the scene does not hold ({} meshes, removed ones included)",
                name(),
                inst.mesh,
                self.meshes.len()
            )));
        };
        let mesh_edges = match (inst.casts && self.edges_on, m.edges) {
            (false, _) => None,
            (true, Some(e)) => Some(e),
            (true, None) => {
                return Err(RuntimeError::Param(format!(
                    "{} casts, but mesh {} was uploaded with no instance that casts and moves, so its edge adjacency was not kept where the placement step reads it: add the mesh again (`Scene::add_mesh`) and place the new one",
                    name(),
                    inst.mesh
                )));
            }
        };
        let world = inst.in_world_space();
        // the placement step binds its buffers whole: each must fit one storage binding
        let storage_limit = gpu.limits.max_storage_buffer_binding_size.min(gpu.limits.max_buffer_size);
        if let Some(p) = self.pools.bound().iter().find(|p| p.buffer.size() > storage_limit) {
            return Err(RuntimeError::Limit {
                what: format!(
                    "{} (bytes; bound whole by the placement step, which the instance added needs)",
                    p.label()
                ),
                needed: p.buffer.size(),
                limit: storage_limit,
            });
        }
        // a mesh uploaded for world space only, now placed: its vertices are copied to where
        // the placement step reads them
        let copy = !world && m.at[0].is_none();
        let me = mesh_edges.map_or([0; 4], |e| e.len);
        let r = self.pools.take(
            gpu,
            &[
                (Which::Meshes, if copy { m.vertices.into() } else { 0 }),
                (Which::Placed, if world { 0 } else { m.vertices.into() }),
                (Which::Edges, me[0].into()),
                (Which::Planes, me[1].into()),
                (Which::Faces, me[2].into()),
                (Which::Claims, me[3].into()),
                (Which::Records, 1),
            ],
        )?;
        let mut mesh = m;
        if copy && let Some(from) = mesh.at[1] {
            let mut encoder = gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("a mesh placed on the GPU"),
            });
            encoder.copy_buffer_to_buffer(
                &self.pools.world.buffer,
                u64::from(from) * 24,
                &self.pools.meshes.buffer,
                u64::from(r[0].start) * 24,
                u64::from(mesh.vertices) * 24,
            );
            gpu.queue.submit([encoder.finish()]);
            mesh.at[0] = Some(r[0].start);
            self.meshes[inst.mesh] = Some(mesh.clone());
        }
        let slot = InstanceSlot {
            mesh: inst.mesh,
            record: r[6].start,
            vertices: (!world).then_some(r[1].start),
            edges: mesh_edges.map(|e| EdgeSpan {
                first: [r[2].start, r[3].start, r[4].start, r[5].start],
                ..e
            }),
            receives: inst.receives,
        };
        let mut span = Spans {
            welded: r[5].start,
            ..Default::default()
        };
        if let (Some(placed), Some(from)) = (slot.vertices, mesh.at[0]) {
            span.vertices = [from, mesh.vertices, placed];
        }
        if let Some(e) = &mesh_edges {
            span.edges = [e.first[0], e.len[0], r[2].start];
            span.planes = [e.first[1], e.len[1], r[3].start];
            span.faces = [e.first[2], e.len[2], r[4].start];
        }
        let range = match draw_range(&mesh, &slot, inst.casts) {
            Ok(range) => range,
            Err(e) => {
                self.free_instance(&slot, &mesh);
                return Err(e);
            }
        };
        let record = record_of(&inst.transform, &span);
        self.write(gpu, Which::Records, slot.record, &record);
        if let (Some(edges), Some(e)) = (&mut self.scene.edges, &mesh_edges) {
            edges.counts.add(&e.counts, 1);
        }
        self.scene.draw.ranges.push(range);
        self.slots.push(slot);
        self.spans.push(span);
        self.moves.push(inst.moves);
        self.transforms.push(inst.transform);
        self.casts.push(inst.casts);
        self.boxes.push(mesh.bbox);
        self.places |= span.vertices[1] > 0 || span.edges[1] > 0;
        // the instance is placed in the next frame (the others again, as they were)
        self.dirty = true;
        self.changed(gpu, mesh_edges.is_some());
        Ok(index)
    }

    /// Remove instance `index` (those after it move down one place): its ranges handed
    /// back, its placed edges zeroed.
    pub fn remove_instance(&mut self, gpu: &Gpu, index: usize) -> Result<()> {
        if index >= self.slots.len() {
            return Err(RuntimeError::Param(format!(
                "no instance {index}: the scene holds {}",
                self.slots.len()
            )));
        }
        let slot = self.slots.remove(index);
        let mesh = self.meshes[slot.mesh]
            .clone()
            .ok_or_else(|| RuntimeError::NotFound(format!("instance {index}'s mesh {} was removed before it", slot.mesh)))?;
        if let Some(e) = &slot.edges {
            // an edge of no face is never a silhouette: the hole stays in the classification
            let mut encoder = gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("a removed instance's edges"),
            });
            encoder.clear_buffer(
                &self.pools.edges.buffer,
                self.pools.edges.offset(e.first[0].into()),
                Some(u64::from(e.len[0]) * 48),
            );
            gpu.queue.submit([encoder.finish()]);
            if let Some(edges) = &mut self.scene.edges {
                edges.counts.add(&e.counts, -1);
            }
        }
        self.free_instance(&slot, &mesh);
        self.scene.draw.ranges.remove(index);
        for v in [&mut self.moves, &mut self.casts] {
            v.remove(index);
        }
        self.spans.remove(index);
        self.transforms.remove(index);
        self.boxes.remove(index);
        self.places = self.spans.iter().any(|s| s.vertices[1] > 0 || s.edges[1] > 0);
        self.dirty = true;
        self.changed(gpu, slot.edges.is_some());
        Ok(())
    }

    /// Remove mesh `index` (the others keep their indices): refused while an instance
    /// places it.
    pub fn remove_mesh(&mut self, gpu: &Gpu, index: usize) -> Result<()> {
        if let Some(k) = self.slots.iter().position(|s| s.mesh == index) {
            return Err(RuntimeError::Param(format!(
                "mesh {index} is placed by instance {k}: remove its instances first"
            )));
        }
        let Some(m) = self.meshes.get_mut(index).and_then(Option::take) else {
            return Err(RuntimeError::Param(format!("no mesh {index} in the scene")));
        };
        if let Some(at) = m.at[0] {
            self.pools.give_back(Which::Meshes, at, m.vertices);
        }
        if let Some(at) = m.at[1] {
            self.pools.world.free(u64::from(at)..u64::from(at) + u64::from(m.vertices));
        }
        if let Some(at) = m.first_index {
            self.pools.give_back(Which::Indices, at, m.elements);
        }
        if let Some(e) = m.edges {
            for (w, k) in [(Which::MeshEdges, 0), (Which::MeshPlanes, 1), (Which::MeshFaces, 2)] {
                self.pools.give_back(w, e.first[k], e.len[k]);
            }
        }
        self.changed(gpu, false);
        Ok(())
    }

    /// The meshes the scene holds (removed ones excluded).
    pub fn mesh_count(&self) -> usize {
        self.meshes.iter().flatten().count()
    }

    /// The instances, in draw order.
    pub fn instance_count(&self) -> usize {
        self.slots.len()
    }

    /// Hand back an instance's ranges.
    fn free_instance(&mut self, slot: &InstanceSlot, mesh: &MeshSlot) {
        if let Some(at) = slot.vertices {
            self.pools.give_back(Which::Placed, at, mesh.vertices);
        }
        if let Some(e) = &slot.edges {
            for (w, k) in [(Which::Edges, 0), (Which::Planes, 1), (Which::Faces, 2), (Which::Claims, 3)] {
                self.pools.give_back(w, e.first[k], e.len[k]);
            }
        }
        self.pools.give_back(Which::Records, slot.record, 1);
    }

    /// Write `bytes` at element `at` of a pool, counted in [`Changes::uploaded`].
    fn write(&mut self, gpu: &Gpu, w: Which, at: u32, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        let pool = self.pools.get(w);
        gpu.queue.write_buffer(&pool.buffer, pool.offset(at.into()), bytes);
        self.changes.uploaded += bytes.len() as u64;
    }

    /// After a change: the scene's buffers as they now are, the draws of the objects that
    /// receive no shadow, the placement step's group when a buffer it binds grew; what the
    /// targets take again counted.
    fn changed(&mut self, gpu: &Gpu, edges: bool) {
        let grown = self.pools.grown();
        let regrouped = grown != self.changes.grown || (self.places && self.group.is_none());
        if regrouped && self.places {
            self.group = Some(self.pools.place_group(&gpu.device, &self.layout));
        }
        if grown != self.changes.grown || edges {
            self.changes.bindings += 1;
        }
        self.changes.grown = grown;
        self.changes.draws += 1;
        let draw = &mut self.scene.draw;
        draw.buffers = self.pools.vertex_buffers();
        draw.indices = self.pools.indices.buffer.clone();
        draw.unshadowed = draw
            .ranges
            .iter()
            .zip(&self.slots)
            .filter(|(_, s)| !s.receives)
            .map(|(r, _)| r.clone())
            .collect();
        if let Some(e) = &mut self.scene.edges {
            e.edges = self.pools.edges.buffer.clone();
            e.planes = self.pools.planes.buffer.clone();
            e.edge_faces = self.pools.faces.buffer.clone();
            e.claims = self.pools.claims.buffer.clone();
            e.extent = self.pools.edges.extent() as u32;
        }
        self.world = world_boxes(&self.boxes, &self.casts, &self.transforms);
    }
}
