//! What the runtime takes from a scene ([`SceneInputs`]: a soup with one camera and light)
//! and a frame ([`Camera`], [`LightInputs`]), and the `Frame` uniform made
//! from it. The uniform's layout has one definition, [`crate::graph::FrameUniform`] (with
//! [`crate::graph::FRAME_WGSL`] and [`crate::graph::FRAME_FIELDS`] derived from it).

use crate::error::{Result, RuntimeError};
use crate::graph::{FrameUniform, SampleViewUniform};

/// One light sample's view, for the passes that render one view per light sample
/// (`views: PerLightSample`; Heidrich et al. 2000). Its near and far bound its own linear
/// depth, as the centre's do.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleView {
    pub light_view: [f32; 16],
    pub light_view_proj: [f32; 16],
    /// The sample's position, world space.
    pub position: [f32; 3],
    pub near: f32,
    pub far: f32,
    /// Element [1][1] of the view's perspective projection (1 / tan(fov / 2)).
    pub light_proj_y: f32,
    /// Weights of the segment of light before the sample and of the one after it (their
    /// share of the light; 0 where there is none). A lone sample takes 1 and 1: each
    /// segment's visibility channels start at one half (section 3.2), so a lit point's
    /// visibilities sum to the weights' half-sums, 1 over the whole light.
    pub weights: [f32; 2],
}

/// A triangle soup with one camera and light, as plain data (column-major matrices): the
/// lab's scenes, made into a [`crate::gpu::Scene`], [`crate::gpu::Sizes`] and a
/// [`crate::gpu::FrameState`].
#[derive(Clone, Debug, PartialEq)]
pub struct SceneInputs {
    /// Interleaved world-space position xyz and normal xyz, three vertices per triangle: a
    /// triangle soup, bound as host geometry of one world-space instance per object
    /// ([`crate::gpu::Geometry::from_soup`], which says what it refuses).
    pub vertices: Vec<f32>,
    /// The scene's meshes as ranges of triangles (indices into `vertices / 18`), each on
    /// one side of `casting_vertices`. Geometry passes find the casters' edges within each
    /// mesh, never across two; empty: the casting triangles are one mesh.
    pub meshes: Vec<std::ops::Range<u32>>,
    /// How many of the first `vertices` are drawn from the light (`Draw::SceneFromLight`):
    /// the shadow casters, listed first; the rest (objects that cast no shadow, such as a
    /// ground plane) are drawn by the camera only. `None`: every vertex casts.
    pub casting_vertices: Option<u32>,
    /// Ranges of `vertices / 6` of the objects that receive no shadow: drawn unshadowed,
    /// they read visibility 1 (runtime/src/receivers.rs). Empty: every object receives.
    pub unshadowed: Vec<std::ops::Range<u32>>,
    pub camera_view_proj: [f32; 16],
    pub camera_position: [f32; 3],
    pub camera_size: (u32, u32),
    pub shadow_size: u32,
    pub light_view: [f32; 16],
    pub light_view_proj: [f32; 16],
    /// xyz position (w = 1) or direction towards the light (w = 0).
    pub light_position: [f32; 4],
    pub near: f32,
    pub far: f32,
    /// Radius or half-extent, world units.
    pub light_size: f32,
    /// Half-extents of the light along the shadow map's u and v axes, world units.
    pub light_half_extents: [f32; 2],
    /// Full angular diameter, radians.
    pub light_angle: f32,
    /// Element [1][1] of the light's projection (1 / tan(fov / 2), or 2 / height for an orthographic light).
    pub light_proj_y: f32,
    pub light_orthographic: bool,
    /// The light's sample views, in order along the light (empty: the scene binds no
    /// per-sample graph).
    pub samples: Vec<SampleView>,
    /// The samples close a loop (the edges of a triangle or rectangle light): the last
    /// one's next is the first.
    pub samples_closed: bool,
    /// The kind of the scene's light, checked against a graph specialised for one
    /// (`PassGraph::specialised`); `None` runs only generic graphs.
    pub light: Option<crate::graph::LightKind>,
}

/// The camera: what a host may change every frame without reallocation
/// ([`crate::gpu::FrameState::camera`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Column-major world-to-clip matrix (WebGPU clip space: depth in [0, 1]).
    pub view_proj: [f32; 16],
    /// World space.
    pub position: [f32; 3],
}

/// One light as the passes see it: what a host may change every frame without
/// reallocation ([`crate::gpu::FrameState::lights`]). The number of light samples is a
/// size: changing it reallocates.
#[derive(Clone, Debug, PartialEq)]
pub struct LightInputs {
    /// Column-major world-to-view and world-to-clip matrices of the light's view.
    pub view: [f32; 16],
    pub view_proj: [f32; 16],
    /// xyz position (w = 1) or direction towards the light (w = 0).
    pub position: [f32; 4],
    pub near: f32,
    pub far: f32,
    /// Radius or half-extent, world units.
    pub size: f32,
    /// Half-extents along the shadow map's u and v axes, world units.
    pub half_extents: [f32; 2],
    /// Full angular diameter, radians.
    pub angle: f32,
    /// Element [1][1] of the projection (1 / tan(fov / 2), or 2 / height orthographic).
    pub proj_y: f32,
    pub orthographic: bool,
    pub samples: Vec<SampleView>,
    pub samples_closed: bool,
    pub kind: Option<crate::graph::LightKind>,
}

fn finite(values: &[f32]) -> bool {
    values.iter().all(|v| v.is_finite())
}

impl Camera {
    /// Refuse a non-finite matrix or position, and a matrix that maps every point to one
    /// (no inverse: an all-zero matrix drew every pixel lit; issue 49).
    pub fn check(&self) -> Result<()> {
        if !(finite(&self.view_proj) && finite(&self.position)) {
            return Err(RuntimeError::Param(format!(
                "the camera's matrix or position is not finite: {:?} at {:?}",
                self.view_proj, self.position
            )));
        }
        let det = sshc_light::glam::Mat4::from_cols_array(&self.view_proj).determinant();
        if !(det.is_finite() && det != 0.0) {
            return Err(RuntimeError::Param(format!(
                "the camera's view-projection matrix has no inverse (determinant {det}): it maps the whole scene to a point or a plane"
            )));
        }
        if self.depth_slope() < 0.0 {
            return Err(RuntimeError::Param(
                "the camera's projection gives nearer points the larger depth (reverse-Z): the runtime's camera depth runs from 0 near to 1 far; give the camera as `Camera::from_reverse_z(view_proj, position)`, which maps it so".into(),
            ));
        }
        Ok(())
    }

    /// A camera whose projection reverses depth (1 at the near plane, 0 or towards 0 far
    /// away, as `sshc_light::perspective_infinite_reverse` and Bevy's cameras give it): its
    /// matrix mapped to the runtime's depth by `z' = w - z` (x, y and w, and so what every
    /// pixel sees, are the host's own, bit for bit; depth `1 - z / w`).
    pub fn from_reverse_z(view_proj: [f32; 16], position: [f32; 3]) -> Camera {
        let mut m = view_proj;
        // column-major: element (row 2, column c) is m[4 c + 2]; row 3 is w
        for c in 0..4 {
            m[4 * c + 2] = m[4 * c + 3] - m[4 * c + 2];
        }
        Camera { view_proj: m, position }
    }

    /// The sign of how normalised depth changes along the view axis (from the camera,
    /// where `w` grows): positive for a forward projection, negative for a reversed one, 0
    /// where `w` is constant (orthographic: the axis's sense cannot be told from the
    /// matrix). Along any line `z / w` is monotonic, with the sign of
    /// `z1 w0 - z0 w1` wherever the line starts.
    fn depth_slope(&self) -> f64 {
        let m = self.view_proj.map(f64::from);
        let row = |r: usize| [m[r], m[4 + r], m[8 + r], m[12 + r]];
        let (rz, rw) = (row(2), row(3));
        let axis = [rw[0], rw[1], rw[2]];
        let len = axis.iter().map(|a| a * a).sum::<f64>().sqrt();
        if len <= 1e-12 * rw[3].abs().max(1.0) {
            return 0.0;
        }
        let p = self.position.map(f64::from);
        let at = |r: [f64; 4]| r[0] * p[0] + r[1] * p[1] + r[2] * p[2] + r[3];
        let along = |r: [f64; 4]| (r[0] * axis[0] + r[1] * axis[1] + r[2] * axis[2]) / len;
        along(rz) * at(rw) - at(rz) * along(rw)
    }
}

impl LightInputs {
    /// A warning where a perspective view's near plane is so close to the light that depth
    /// precision and near-plane kernels suffer ([`sshc_light::LightView::depth_warning`]:
    /// a caster reaches the light's plane). A host shows it once; the frame still runs.
    pub fn depth_warning(&self) -> Option<String> {
        sshc_light::depth_warning(self.near, self.far, self.orthographic)
    }

    /// Become `from`, in place: the samples' vector keeps its capacity (a derived
    /// `clone_from` would allocate a new one every frame).
    pub(crate) fn assign(&mut self, from: &LightInputs) {
        let mut samples = std::mem::take(&mut self.samples);
        samples.clone_from(&from.samples);
        *self = LightInputs {
            samples,
            ..from.without_samples()
        };
    }

    /// A copy without its sample views (nothing allocated).
    fn without_samples(&self) -> LightInputs {
        LightInputs {
            view: self.view,
            view_proj: self.view_proj,
            position: self.position,
            near: self.near,
            far: self.far,
            size: self.size,
            half_extents: self.half_extents,
            angle: self.angle,
            proj_y: self.proj_y,
            orthographic: self.orthographic,
            samples: Vec::new(),
            samples_closed: self.samples_closed,
            kind: self.kind,
        }
    }

    /// Refuse non-finite matrices, positions or sizes, and an empty depth range.
    pub fn check(&self, light: usize) -> Result<()> {
        // every value, without collecting them (this runs on every `set_light`)
        let scalars = [self.near, self.far, self.size, self.angle, self.proj_y];
        let views = self
            .view
            .iter()
            .chain(&self.view_proj)
            .chain(&self.position)
            .chain(&self.half_extents);
        let samples = self.samples.iter().flat_map(|s| {
            s.light_view
                .iter()
                .chain(&s.light_view_proj)
                .chain(&s.position)
                .chain([&s.near, &s.far, &s.light_proj_y])
        });
        if !scalars.iter().chain(views).chain(samples).all(|v| v.is_finite()) {
            return Err(RuntimeError::Param(format!(
                "light {light}: a matrix, position or size is not finite"
            )));
        }
        if self.far <= self.near {
            return Err(RuntimeError::Param(format!(
                "light {light}: its depth range [{}, {}] is empty",
                self.near, self.far
            )));
        }
        Ok(())
    }

    /// The `Frame` uniform of this light seen by `camera`. Every render target of the graph
    /// has the shadow map's size, so `target_size` is the shadow map's.
    pub fn frame(&self, camera: &Camera, shadow_size: u32) -> FrameUniform {
        let n = shadow_size as f32;
        let range = (self.far - self.near).max(f32::MIN_POSITIVE);
        let p = camera.position;
        let texel = 2.0 / (self.proj_y.max(f32::MIN_POSITIVE) * n);
        FrameUniform {
            light_view_proj: self.view_proj,
            light_view: self.view,
            camera_view_proj: camera.view_proj,
            light_position: self.position,
            camera_position: [p[0], p[1], p[2], 1.0],
            depth_range: [self.near, self.far, 1.0 / range, 0.0],
            shadow_size: [n, n, 1.0 / n, 1.0 / n],
            light_size: [self.size, self.angle, self.half_extents[0], self.half_extents[1]],
            target_size: [n, n, 1.0 / n, 1.0 / n],
            texel_world: if self.orthographic {
                [0.0, texel, 0.0, 0.0]
            } else {
                [texel, 0.0, 0.0, 0.0]
            },
            sample: [0.0, self.samples.len() as f32, if self.samples_closed { 1.0 } else { 0.0 }, 0.0],
            // `counters.x`, the frame index, is written by `Targets::prepare` for each frame
            counters: [0.0; 4],
        }
    }

    /// The `Frame` uniform of sample view `k`: the centre's, with the sample's matrices,
    /// position, depth range and texel size, and `sample.x = k`.
    pub fn sample_frame(&self, camera: &Camera, shadow_size: u32, k: usize) -> Option<FrameUniform> {
        let s = self.samples.get(k)?;
        let mut f = self.frame(camera, shadow_size);
        let n = shadow_size as f32;
        f.light_view_proj = s.light_view_proj;
        f.light_view = s.light_view;
        f.light_position = [s.position[0], s.position[1], s.position[2], 1.0];
        f.depth_range = [s.near, s.far, 1.0 / (s.far - s.near).max(f32::MIN_POSITIVE), 0.0];
        f.texel_world = [2.0 / (s.light_proj_y.max(f32::MIN_POSITIVE) * n), 0.0, 0.0, 0.0];
        f.sample[0] = k as f32;
        Some(f)
    }

    /// The `LightSamples` uniform: every sample's view.
    pub fn light_samples(&self, shadow_size: u32) -> Vec<SampleViewUniform> {
        let mut out = Vec::with_capacity(self.samples.len());
        self.write_light_samples(shadow_size, &mut out);
        out
    }

    /// [`LightInputs::light_samples`] into `out`, in place (its capacity kept).
    pub(crate) fn write_light_samples(&self, shadow_size: u32, out: &mut Vec<SampleViewUniform>) {
        let n = shadow_size as f32;
        out.clear();
        out.extend(self.samples.iter().map(|s| SampleViewUniform {
            view_proj: s.light_view_proj,
            view: s.light_view,
            position: [s.position[0], s.position[1], s.position[2], 1.0],
            depth_range: [s.near, s.far, 1.0 / (s.far - s.near).max(f32::MIN_POSITIVE), 0.0],
            weights: [
                s.weights[0],
                s.weights[1],
                2.0 / (s.light_proj_y.max(f32::MIN_POSITIVE) * n),
                1.0 / s.light_proj_y.max(f32::MIN_POSITIVE),
            ],
        }));
    }
}

impl SceneInputs {
    /// The inputs of `light` seen by `camera` at these sizes, with no triangle soup
    /// (`vertices` and `meshes` empty, every vertex casting): what a binding of host
    /// geometry takes, and the base a soup is added to.
    pub fn of(camera: &Camera, light: &LightInputs, camera_size: (u32, u32), shadow_size: u32) -> SceneInputs {
        SceneInputs {
            vertices: Vec::new(),
            meshes: Vec::new(),
            casting_vertices: None,
            unshadowed: Vec::new(),
            camera_view_proj: camera.view_proj,
            camera_position: camera.position,
            camera_size,
            shadow_size,
            light_view: light.view,
            light_view_proj: light.view_proj,
            light_position: light.position,
            near: light.near,
            far: light.far,
            light_size: light.size,
            light_half_extents: light.half_extents,
            light_angle: light.angle,
            light_proj_y: light.proj_y,
            light_orthographic: light.orthographic,
            samples: light.samples.clone(),
            samples_closed: light.samples_closed,
            light: light.kind,
        }
    }

    /// The scene's camera.
    pub fn camera(&self) -> Camera {
        Camera {
            view_proj: self.camera_view_proj,
            position: self.camera_position,
        }
    }

    /// The scene's light.
    pub fn light_inputs(&self) -> LightInputs {
        LightInputs {
            view: self.light_view,
            view_proj: self.light_view_proj,
            position: self.light_position,
            near: self.near,
            far: self.far,
            size: self.light_size,
            half_extents: self.light_half_extents,
            angle: self.light_angle,
            proj_y: self.light_proj_y,
            orthographic: self.light_orthographic,
            samples: self.samples.clone(),
            samples_closed: self.samples_closed,
            kind: self.light,
        }
    }

    /// The `Frame` uniform of this scene ([`LightInputs::frame`]).
    pub fn frame(&self) -> FrameUniform {
        self.light_inputs().frame(&self.camera(), self.shadow_size)
    }

    /// The `Frame` uniform of sample view `k` ([`LightInputs::sample_frame`]).
    pub fn sample_frame(&self, k: usize) -> Option<FrameUniform> {
        self.light_inputs().sample_frame(&self.camera(), self.shadow_size, k)
    }

    /// The `LightSamples` uniform ([`LightInputs::light_samples`]).
    pub fn light_samples(&self) -> Vec<SampleViewUniform> {
        self.light_inputs().light_samples(self.shadow_size)
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::{
        FRAME_FIELDS, FRAME_SIZE, FRAME_WGSL, FrameField, FrameUniform, LIGHT_SAMPLES_SIZE, LIGHT_SAMPLES_WGSL, MAX_LIGHT_SAMPLES,
        SAMPLE_VIEW_FIELDS, SAMPLE_VIEW_SIZE, SampleViewUniform, field_offset, frame_offset,
    };

    /// naga's layout of struct `name` in `wgsl` (name, offset, size per member; struct
    /// size), and the module and its layouter for further questions.
    fn naga_layout(wgsl: &str, name: &str) -> (Vec<(String, u32, u32)>, u32, naga::Module, naga::proc::Layouter) {
        let module = naga::front::wgsl::parse_str(wgsl).unwrap_or_else(|e| panic!("{}", e.emit_to_string(wgsl)));
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("the WGSL declares `{name}`"));
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("`{name}` is not a struct")
        };
        assert_eq!(layouter[handle].size, *span);
        let members = members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset, layouter[m.ty].size))
            .collect();
        let span = *span;
        (members, span, module, layouter)
    }

    /// The field table, the Rust struct and the WGSL declaration of one uniform struct
    /// agree with naga's layout of the WGSL.
    fn agrees(wgsl: &str, name: &str, fields: &[FrameField], size: u32, rust: &[usize], rust_size: usize) {
        let (members, span, ..) = naga_layout(wgsl, name);
        assert_eq!(members.len(), fields.len(), "{name}");
        for (i, (f, (member, offset, bytes))) in fields.iter().zip(&members).enumerate() {
            assert_eq!(f.name, member, "{name}: field {i}");
            assert_eq!(field_offset(fields, i), *offset, "{name}: offset of `{member}`");
            assert_eq!(f.ty.size(), *bytes, "{name}: size of `{member}`");
            assert_eq!(rust[i], *offset as usize, "{name}: offset of the Rust field `{member}`");
            assert!(wgsl.contains(&format!("    {member}: {},\n", f.ty.wgsl())));
        }
        assert_eq!((span, rust_size), (size, size as usize), "{name}: size");
    }

    #[test]
    fn frame_layout_is_nagas() {
        agrees(
            FRAME_WGSL,
            "Frame",
            FRAME_FIELDS,
            FRAME_SIZE,
            &FrameUniform::rust_offsets(),
            std::mem::size_of::<FrameUniform>(),
        );
        assert_eq!(frame_offset(3), field_offset(FRAME_FIELDS, 3));
    }

    /// `LightSamples`: each `SampleView` as naga lays it out, the array as long as
    /// `MAX_LIGHT_SAMPLES` with naga's stride, and the bytes at those offsets.
    #[test]
    fn light_samples_layout_is_nagas() {
        agrees(
            LIGHT_SAMPLES_WGSL,
            "SampleView",
            SAMPLE_VIEW_FIELDS,
            SAMPLE_VIEW_SIZE,
            &SampleViewUniform::rust_offsets(),
            std::mem::size_of::<SampleViewUniform>(),
        );
        let (members, span, module, layouter) = naga_layout(LIGHT_SAMPLES_WGSL, "LightSamples");
        assert_eq!(span, LIGHT_SAMPLES_SIZE);
        assert_eq!(members.len(), 1);
        let array = module
            .types
            .iter()
            .find_map(|(h, t)| {
                let naga::TypeInner::Array { size, stride, .. } = t.inner else {
                    return None;
                };
                Some((h, size, stride))
            })
            .expect("an array of views");
        assert_eq!(
            array.1,
            naga::ArraySize::Constant(std::num::NonZeroU32::new(MAX_LIGHT_SAMPLES).unwrap())
        );
        assert_eq!(array.2, SAMPLE_VIEW_SIZE);
        assert_eq!(layouter[array.0].size, LIGHT_SAMPLES_SIZE);
        // view k's weights at k * stride + the field's offset
        let views: Vec<SampleViewUniform> = (0..3)
            .map(|k| SampleViewUniform {
                weights: [k as f32 + 1.0, 0.0, 0.0, 0.0],
                ..Default::default()
            })
            .collect();
        let bytes = SampleViewUniform::light_samples_bytes(&views);
        assert_eq!(bytes.len(), LIGHT_SAMPLES_SIZE as usize);
        let weights = field_offset(SAMPLE_VIEW_FIELDS, 4) as usize;
        for k in 0..3 {
            let at = k * SAMPLE_VIEW_SIZE as usize + weights;
            assert_eq!(f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()), k as f32 + 1.0);
        }
        assert_eq!(
            bytes.chunks_exact(4).filter(|w| w.iter().any(|b| *b != 0)).count(),
            3,
            "only the three weights"
        );
    }

    /// The structs the runtime shares with its own shaders and the compiler's (`Edge`, a
    /// storage array's element; `Placement` and `Slices`, uniforms): their field tables,
    /// Rust structs and WGSL as naga lays them out, and each field's bytes at its offset
    /// (u32 fields too: a value per field, read back where naga puts it).
    #[test]
    fn the_shared_structs_layouts_are_nagas() {
        use sshc_graph::{
            EDGE_FIELDS, EDGE_SIZE, EDGE_WGSL, GpuEdge, PLACEMENT_FIELDS, PLACEMENT_SIZE, PLACEMENT_WGSL, PlacementUniform, SLICES_FIELDS,
            SLICES_SIZE, SLICES_WGSL, SlicesUniform,
        };
        let rust = |offsets: Vec<usize>, size: usize| (offsets, size);
        for (wgsl, name, fields, size, (offsets, rust_size)) in [
            (
                EDGE_WGSL,
                "Edge",
                EDGE_FIELDS,
                EDGE_SIZE,
                rust(GpuEdge::rust_offsets(), std::mem::size_of::<GpuEdge>()),
            ),
            (
                PLACEMENT_WGSL,
                "Placement",
                PLACEMENT_FIELDS,
                PLACEMENT_SIZE,
                rust(PlacementUniform::rust_offsets(), std::mem::size_of::<PlacementUniform>()),
            ),
            (
                SLICES_WGSL,
                "Slices",
                SLICES_FIELDS,
                SLICES_SIZE,
                rust(SlicesUniform::rust_offsets(), std::mem::size_of::<SlicesUniform>()),
            ),
        ] {
            agrees(wgsl, name, fields, size, &offsets, rust_size);
        }
        // an edge of an array strides by its size: 48 bytes, as the adjacency writes them
        let (_, span, ..) = naga_layout(&format!("{EDGE_WGSL}@group(0) @binding(0) var<storage> e: array<Edge>;"), "Edge");
        assert_eq!((span, EDGE_SIZE), (48, 48));
        let e = GpuEdge {
            a: [1.0, 2.0, 3.0],
            first_face: 4,
            b: [5.0, 6.0, 7.0],
            face_count: 8,
            ia: 9,
            ib: 10,
            pad: [11, 12],
        };
        let bytes = e.to_bytes();
        let (members, ..) = naga_layout(EDGE_WGSL, "Edge");
        let word = |name: &str, k: usize| {
            let at = members.iter().find(|m| m.0 == name).unwrap().1 as usize + 4 * k;
            <[u8; 4]>::try_from(&bytes[at..at + 4]).unwrap()
        };
        assert_eq!([f32::from_le_bytes(word("a", 2)), f32::from_le_bytes(word("b", 0))], [3.0, 5.0]);
        let words = [
            ("first_face", 0, 4),
            ("face_count", 0, 8),
            ("ia", 0, 9),
            ("ib", 0, 10),
            ("pad", 1, 12),
        ];
        for (name, k, v) in words {
            assert_eq!(u32::from_le_bytes(word(name, k)), v, "{name}");
        }
    }

    #[test]
    fn frame_bytes_put_each_field_at_its_offset() {
        let mut f = FrameUniform::default();
        f.light_view[1] = 2.0;
        f.texel_world[3] = 3.0;
        let bytes = f.to_bytes();
        assert_eq!(bytes.len(), FRAME_SIZE as usize);
        let at = |i: usize| f32::from_le_bytes(bytes[i..i + 4].try_into().unwrap());
        let (members, ..) = naga_layout(FRAME_WGSL, "Frame");
        let offset = |name: &str| members.iter().find(|m| m.0 == name).unwrap().1 as usize;
        assert_eq!(at(offset("light_view") + 4), 2.0);
        assert_eq!(at(offset("texel_world") + 12), 3.0);
        assert_eq!(bytes.chunks_exact(4).filter(|w| w.iter().any(|b| *b != 0)).count(), 2);
    }
}
