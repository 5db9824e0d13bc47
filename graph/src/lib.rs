//! The pass graph: resources, passes and the shader modules that run them, plus the
//! binding conventions every generated module follows.
//!
//! Conventions shared by the compiler and the runtime:
//! - `@group(0) @binding(0)`: the [`FRAME_WGSL`] uniform `frame` (light and camera matrices,
//!   depth range, sizes), filled by the runtime each frame.
//! - `@group(0) @binding(1)`: the technique's `Params` uniform, present when
//!   [`PassGraph::params_size`] > 0; every field is 4 bytes at [`ParamDecl::offset`].
//! - `@group(0) @binding(2)`: a filtering sampler (linear, mipmap linear, clamp to edge),
//!   present when [`Step::sampler`] is true.
//! - `@group(0) @binding(3)`: the [`LIGHT_SAMPLES_WGSL`] uniform `light_samples` (every
//!   light sample's view), present when [`Step::light_samples`] is true. A step of a
//!   `PerLightSample` pass runs once per sample k with view k's `frame` (`sample.x = k`).
//! - `@group(1) @binding(i)`: the textures in [`Step::reads`], in order; a summed-area table
//!   ([`Format::SummedAreaU32`], [`Format::SummedAreaF32`]) is a read-only storage buffer
//!   `array<vec4<u32>>` (or `array<vec4<f32>>`), one element per texel, rows of the shadow map's width, layers one after another.
//! - `@group(2) @binding(i)`: compute steps only: the tables in [`Step::writes`], read-write.
//! - Scene draws use one vertex buffer: `@location(0)` position and `@location(1)` normal,
//!   `vec3<f32>` each, interleaved (24-byte stride), in world space.

#![deny(clippy::wildcard_enum_match_arm)]

pub mod cost;

mod lights;
mod schema;
mod uniforms;
mod validate;
mod wgsl;

pub use lights::*;
pub use schema::*;
pub use uniforms::*;
pub use validate::*;
pub use wgsl::*;

#[cfg(test)]
mod tests {
    use super::*;

    /// The format table read both ways: each texture format is the one `Format::of` gives
    /// for its layout, its size is its components' (WGSL's sizes: 1, 2, 4 bytes), and the
    /// families the runtime and the compiler ask about are the ones WebGPU names so.
    #[test]
    fn each_format_is_found_from_its_layout() {
        for f in Format::ALL {
            let (component, count) = f.layout();
            assert_eq!(f.bytes_per_texel(), component.bytes() * count, "{f:?}");
            if f.is_table() {
                assert_eq!(f.bytes_per_texel(), 16, "{f:?}: a vec4 of 32-bit sums");
            } else {
                assert_eq!(Format::of(component, count), Some(f), "{f:?}");
                let name = format!("{f:?}");
                assert_eq!(f.is_norm16(), name.ends_with("16Unorm"), "{f:?}");
                assert_eq!(f.is_float32(), name.ends_with("32Float"), "{f:?}");
                assert_eq!(component.is_unorm(), name.ends_with("Unorm"), "{f:?}");
            }
        }
        assert_eq!(Format::of(Component::Float32, 3), None);
        assert_eq!(Format::of(Component::Uint32, 4), None, "a u32 texel is a table's alone");
    }

    fn tiny() -> PassGraph {
        PassGraph {
            version: SCHEMA_VERSION,
            technique: "t".into(),
            title: None,
            paper: None,
            lights: vec![LightModel::Any],
            params: vec![],
            params_size: 0,
            textures: vec![TextureDecl {
                name: "z".into(),
                format: Format::R32Float,
                layers: 1,
                extent: Extent::ShadowMap,
                mips: false,
                transient: false,
                channels: vec![],
                views: 1,
            }],
            samples: 1,
            buffers: vec![],
            passes: vec![PassDecl {
                name: "depth".into(),
                kind: PassKind::Depth,
                views: Views::LightCenter,
                shader: "t.depth.wgsl".into(),
                steps: vec![Step {
                    vertex: Some("vs".into()),
                    fragment: Some("fs".into()),
                    compute: None,
                    draw: Draw::SceneFromLight,
                    reads: vec![],
                    writes: vec![Target {
                        texture: "z".into(),
                        layer: 0,
                    }],
                    params: false,
                    sampler: false,
                    light_samples: false,
                    cost: OpCount::default(),
                }],
            }],
            removed: vec![],
            specialised: None,
            shadow_map: None,
        }
    }

    #[test]
    fn light_kinds_round_trip() {
        for (i, k) in LightKind::ALL.into_iter().enumerate() {
            assert_eq!(k as usize, i);
            assert_eq!(LightKind::from_name(k.name()), Some(k));
            let m = LightModel::of(k, 4);
            assert_eq!(m.kind(), Some(k));
            assert!(m.accepts(k) && LightModel::Any.accepts(k));
            // the model's serialised name is the kind's
            assert!(ron::to_string(&m).unwrap().starts_with(k.name()));
        }
        assert_eq!(LightKind::Triangle as usize + 1, LightKind::ALL.len());
        assert_eq!(LightModel::Any.kind(), None);
    }

    /// A graph's `shadow_map` (a tuned technique's map size) round-trips, and a size no
    /// device can hold is refused.
    #[test]
    fn a_shadow_map_size_round_trips_and_is_bounded() {
        let mut g = tiny();
        g.shadow_map = Some(1024);
        assert_eq!(PassGraph::from_ron(&g.to_ron()).unwrap().shadow_map, Some(1024));
        for bad in [0, MAX_SHADOW_MAP + 1, u32::MAX] {
            g.shadow_map = Some(bad);
            assert_eq!(PassGraph::from_ron(&g.to_ron()), Err(GraphError::ShadowMap(bad)));
        }
        // absent: not written, and an old graph without it reads as none
        g.shadow_map = None;
        assert!(!g.to_ron().contains("shadow_map"));
    }

    /// Camera-sized textures (a Shade's debug outputs) are written by a Shade's camera
    /// steps only, have one layer and no mip chain, and no step reads them.
    #[test]
    fn camera_sized_textures_are_a_shades_camera_steps_own() {
        let shade = |draw: Draw, reads: bool| {
            let mut g = tiny();
            g.textures.push(TextureDecl {
                name: format!("{DEBUG_PREFIX}x"),
                extent: Extent::Camera,
                ..g.textures[0].clone()
            });
            let (vertex, fragment, compute) = if draw.is_dispatch() {
                (None, None, Some("cs".to_string()))
            } else {
                (Some("vs".to_string()), Some("fs".to_string()), None)
            };
            let mut steps = vec![];
            if draw == Draw::ComputePixels {
                steps.push(Step {
                    draw: Draw::CameraGBuffer,
                    writes: vec![],
                    ..g.passes[0].steps[0].clone()
                });
            }
            steps.push(Step {
                vertex,
                fragment,
                compute,
                draw,
                writes: vec![Target {
                    texture: "debug_x".into(),
                    layer: 0,
                }],
                ..g.passes[0].steps[0].clone()
            });
            g.passes.push(PassDecl {
                name: "shade".into(),
                kind: PassKind::Shade,
                views: Views::LightCenter,
                shader: "t.shade.wgsl".into(),
                steps,
            });
            if reads {
                // a later pass reading the output
                g.passes.push(PassDecl {
                    name: "after".into(),
                    kind: PassKind::Map,
                    views: Views::LightCenter,
                    shader: "t.after.wgsl".into(),
                    steps: vec![Step {
                        draw: Draw::FullScreen,
                        reads: vec![Binding {
                            binding: 0,
                            texture: "debug_x".into(),
                            view: View::Base,
                        }],
                        ..g.passes[0].steps[0].clone()
                    }],
                });
            }
            g
        };
        for draw in [Draw::SceneFromCamera, Draw::ComputePixels] {
            let g = shade(draw.clone(), false);
            assert_eq!(PassGraph::from_ron(&g.to_ron()).as_ref(), Ok(&g), "{draw:?}");
            // a step that reads it
            let e = PassGraph::from_ron(&shade(draw.clone(), true).to_ron()).expect_err("read");
            assert!(
                matches!(&e, GraphError::Step { message, .. } if message.contains("reads camera-sized")),
                "{e}"
            );
            // two layers, or a mip chain
            for (layers, mips) in [(2, false), (1, true)] {
                let mut g = shade(draw.clone(), false);
                g.textures[1].layers = layers;
                g.textures[1].mips = mips;
                let e = PassGraph::from_ron(&g.to_ron()).expect_err("shape");
                assert!(matches!(&e, GraphError::Texture { field: "extent", .. }), "{e}");
            }
        }
        // written from the light
        let mut g = tiny();
        g.textures[0].extent = Extent::Camera;
        let e = PassGraph::from_ron(&g.to_ron()).expect_err("from the light");
        assert!(
            matches!(&e, GraphError::Step { pass, message } if pass == "depth" && message.contains("camera-sized")),
            "{e}"
        );
        // a camera step writing a shadow-map-sized texture
        let mut g = shade(Draw::SceneFromCamera, false);
        g.textures[1].extent = Extent::ShadowMap;
        let e = PassGraph::from_ron(&g.to_ron()).expect_err("a shadow-map target of the camera");
        assert!(matches!(&e, GraphError::Step { pass, .. } if pass == "shade"), "{e}");
    }

    #[test]
    fn refuses_channel_tables_that_do_not_describe_the_storage() {
        let channel = |bias: f64, scale: f64, range: (f64, f64), layer: u32, component: u32| ChannelDecl {
            name: "z".into(),
            layer,
            component,
            bias,
            scale,
            range,
        };
        let ok = channel(0.0, 1.0, (0.0, 1.0), 0, 0);
        let mut g = tiny();
        g.textures[0].channels = vec![ok.clone()];
        assert!(PassGraph::from_ron(&g.to_ron()).is_ok());
        for bad in [
            channel(f64::NAN, 1.0, (0.0, 1.0), 0, 0),
            channel(0.0, f64::INFINITY, (0.0, 1.0), 0, 0),
            channel(0.0, 0.0, (0.0, 1.0), 0, 0),
            channel(0.0, 1.0, (f64::NAN, 1.0), 0, 0),
            channel(0.0, 1.0, (1.0, 0.0), 0, 0),
            channel(0.0, 1.0, (0.0, 1.0), 1, 0),
            channel(0.0, 1.0, (0.0, 1.0), 0, 4),
        ] {
            let mut g = tiny();
            g.textures[0].channels = vec![bad.clone()];
            let e = PassGraph::from_ron(&g.to_ron()).expect_err("refused");
            assert!(
                matches!(&e, GraphError::Texture { field: "channels", message, .. } if message.starts_with("channel `z`")),
                "{bad:?}: {e:?}"
            );
        }
    }

    #[test]
    fn steps_name_the_entry_points_their_draw_needs() {
        let mut g = tiny();
        g.passes[0].steps[0].compute = Some("cs".into());
        let e = PassGraph::from_ron(&g.to_ron()).expect_err("a draw with a compute entry");
        assert!(
            matches!(&e, GraphError::Step { message, .. } if message.contains("no compute entry")),
            "{e}"
        );
        let mut g = tiny();
        g.passes[0].steps[0].draw = Draw::ComputeTexels;
        let e = PassGraph::from_ron(&g.to_ron()).expect_err("a dispatch with raster entries");
        assert!(
            matches!(&e, GraphError::Step { message, .. } if message.contains("needs a compute entry point")),
            "{e}"
        );
    }

    /// A deferred Shade: a `CameraGBuffer` step, then a `ComputePixels` step reading it, in
    /// a Shade pass only.
    #[test]
    fn a_deferred_shade_draws_its_g_buffer_before_reading_it() {
        let shade = |draws: &[Draw]| {
            let mut g = tiny();
            let step = g.passes[0].steps[0].clone();
            g.passes.push(PassDecl {
                name: "shade".into(),
                kind: PassKind::Shade,
                views: Views::LightCenter,
                shader: "t.shade.wgsl".into(),
                steps: draws
                    .iter()
                    .map(|d| {
                        let mut s = step.clone();
                        s.writes.clear();
                        s.draw = d.clone();
                        if d.is_dispatch() {
                            (s.vertex, s.fragment, s.compute) = (None, None, Some("cs_shade".into()));
                        }
                        s
                    })
                    .collect(),
            });
            g
        };
        let ok = shade(&[Draw::CameraGBuffer, Draw::ComputePixels]);
        assert_eq!(PassGraph::from_ron(&ok.to_ron()).map(|g| g.passes.len()), Ok(2));
        let e = PassGraph::from_ron(&shade(&[Draw::ComputePixels]).to_ron()).expect_err("no G-buffer drawn");
        assert!(
            matches!(&e, GraphError::Step { message, .. } if message.contains("no earlier CameraGBuffer step")),
            "{e}"
        );
        let e = PassGraph::from_ron(&shade(&[Draw::ComputePixels, Draw::CameraGBuffer]).to_ron()).expect_err("read before drawn");
        assert!(
            matches!(&e, GraphError::Step { message, .. } if message.contains("no earlier CameraGBuffer step")),
            "{e}"
        );
        let mut g = ok.clone();
        g.passes[1].kind = PassKind::Map;
        let e = PassGraph::from_ron(&g.to_ron()).expect_err("a G-buffer in a Map pass");
        assert!(
            matches!(&e, GraphError::Step { message, .. } if message.contains("belongs to a Shade pass")),
            "{e}"
        );
    }

    #[test]
    fn compute_steps_store_only_into_storage_formats() {
        let with = |format: Format| {
            let mut g = tiny();
            g.textures[0].format = format;
            let s = &mut g.passes[0].steps[0];
            (s.vertex, s.fragment, s.compute, s.draw) = (None, None, Some("cs".into()), Draw::ComputeTexels);
            PassGraph::from_ron(&g.to_ron())
        };
        for f in [
            Format::R32Float,
            Format::Rg32Float,
            Format::Rgba32Float,
            Format::Rgba16Float,
            Format::Rgba8Unorm,
        ] {
            assert!(f.storable() && with(f).is_ok(), "{f:?}");
        }
        for f in [
            Format::R8Unorm,
            Format::Rg8Unorm,
            Format::R16Float,
            Format::Rg16Float,
            Format::R16Unorm,
            Format::Rgba16Unorm,
        ] {
            let e = with(f).expect_err("refused");
            assert!(
                matches!(&e, GraphError::Texture { field: "format", message, .. } if message.contains("not a storage format")),
                "{f:?}: {e:?}"
            );
        }
    }

    #[test]
    fn round_trip() {
        let g = tiny();
        assert_eq!(PassGraph::from_ron(&g.to_ron()).unwrap(), g);
    }

    #[test]
    fn refuses_wrong_version_paths_and_names() {
        let mut g = tiny();
        g.version = 99;
        assert_eq!(
            PassGraph::from_ron(&g.to_ron()),
            Err(GraphError::Version {
                found: 99,
                expected: SCHEMA_VERSION
            })
        );
        let mut g = tiny();
        g.passes[0].shader = "../evil.wgsl".into();
        assert!(matches!(PassGraph::from_ron(&g.to_ron()), Err(GraphError::Path { .. })));
        let mut g = tiny();
        g.passes[0].steps[0].writes[0].texture = "nope".into();
        assert!(matches!(PassGraph::from_ron(&g.to_ron()), Err(GraphError::Reference { .. })));
        assert!(matches!(
            PassGraph::from_ron("PassGraph(version: 1"),
            Err(GraphError::Syntax { .. })
        ));
    }

    /// `tiny` plus a param and a Shade pass reading the depth: a valid graph as RON text.
    fn valid_text() -> String {
        let mut g = tiny();
        g.params.push(ParamDecl {
            name: "bias".into(),
            ty: ParamType::F32,
            value: 0.5,
            range: Some((0.0, 1.0)),
            offset: None,
            doc: None,
        });
        let mut shade = g.passes[0].clone();
        shade.name = "shade".into();
        shade.kind = PassKind::Shade;
        shade.steps[0].writes.clear();
        shade.steps[0].reads.push(Binding {
            binding: 0,
            texture: "z".into(),
            view: View::All,
        });
        g.passes.push(shade);
        let text = g.to_ron();
        assert_eq!(PassGraph::from_ron(&text).unwrap(), g);
        text
    }

    /// `valid_text` with the one occurrence of `from` replaced.
    fn changed(from: &str, to: &str) -> Result<PassGraph, GraphError> {
        let text = valid_text();
        assert_eq!(text.matches(from).count(), 1, "`{from}` in {text}");
        PassGraph::from_ron(&text.replacen(from, to, 1))
    }

    #[test]
    fn refuses_unknown_fields() {
        let e = changed("params_size: 0,", "params_size: 0, extra: 1,").unwrap_err();
        assert!(matches!(e, GraphError::Syntax { .. }) && e.to_string().contains("extra"), "{e}");
        let e = changed("mips: false,", "mips: false, sparse: true,").unwrap_err();
        assert!(e.to_string().contains("sparse"), "{e}");
    }

    /// A graph in memory is checked as its text is, without the text (issue 49: the
    /// runtime wrote every graph out and parsed it again to validate it): the same graphs
    /// pass, and those from_ron refuses are refused with the same error.
    #[test]
    fn a_graph_in_memory_is_checked_as_its_text_is() {
        let good = PassGraph::from_ron(&valid_text()).unwrap();
        let valid = ValidGraph::try_from(good.clone()).unwrap();
        assert_eq!(*valid, good);
        assert_eq!(valid.into_inner(), good);
        type Edit = Box<dyn Fn(&mut PassGraph)>;
        let edits: [(&str, Edit); 5] = [
            ("a NaN param", Box::new(|g| g.params[0].value = f64::NAN)),
            ("another version", Box::new(|g| g.version += 1)),
            ("no samples", Box::new(|g| g.samples = 0)),
            (
                "a texture twice",
                Box::new(|g| {
                    let t = g.textures[0].clone();
                    g.textures.push(t)
                }),
            ),
            (
                "a shader path out of the folder",
                Box::new(|g| g.passes[0].shader = "../x.wgsl".into()),
            ),
        ];
        for (what, edit) in edits {
            let mut g = good.clone();
            edit(&mut g);
            let in_memory = ValidGraph::try_from(g.clone()).unwrap_err();
            let from_text = PassGraph::from_ron(&g.to_ron()).unwrap_err();
            assert_eq!(in_memory.to_string(), from_text.to_string(), "{what}");
        }
    }

    #[test]
    fn refuses_nan_param() {
        let e = changed("value: 0.5,", "value: NaN,").unwrap_err();
        assert!(matches!(&e, GraphError::Param { param, .. } if param == "bias"), "{e}");
        assert!(e.to_string().contains("`bias`") && e.to_string().contains("finite"), "{e}");
    }

    #[test]
    fn refuses_infinite_param() {
        let e = changed("value: 0.5,", "value: inf,").unwrap_err();
        assert!(matches!(&e, GraphError::Param { param, .. } if param == "bias"), "{e}");
    }

    #[test]
    fn refuses_param_outside_its_range() {
        let e = changed("value: 0.5,", "value: 1.5,").unwrap_err();
        assert!(e.to_string().contains("outside its range"), "{e}");
        let e = changed("range: Some((0.0, 1.0)),", "range: Some((0.0, inf)),").unwrap_err();
        assert!(matches!(&e, GraphError::Param { param, .. } if param == "bias"), "{e}");
    }

    #[test]
    fn scene_facts_round_trip_and_a_depth_floor_outside_0_1_is_refused() {
        let mut g = tiny();
        let facts = |depth_floor| SceneFacts {
            scene: "scenes/contact.ron".into(),
            light: LightKind::Sphere,
            depth_floor,
        };
        g.specialised = Some(facts(Some(0.25)));
        assert_eq!(PassGraph::from_ron(&g.to_ron()).unwrap().specialised, Some(facts(Some(0.25))));
        // absent: the facts of graphs from before the field
        g.specialised = Some(facts(None));
        assert!(!g.to_ron().contains("depth_floor"));
        assert_eq!(PassGraph::from_ron(&g.to_ron()).unwrap().specialised, Some(facts(None)));
        for bad in [-0.5, 1.5, f32::NAN, f32::INFINITY] {
            g.specialised = Some(facts(Some(bad)));
            let e = PassGraph::from_ron(&g.to_ron()).unwrap_err();
            assert!(
                matches!(e, GraphError::Facts(_)) && e.to_string().contains("depth_floor"),
                "{bad}: {e}"
            );
        }
    }

    /// The casters' least depth: vertices in front of the near plane clamp to 0, the
    /// non-casting ones are skipped, no caster gives none.
    #[test]
    fn caster_depth_floor_takes_the_least_normalised_depth_of_the_casters() {
        // identity view: view-space z is the world z; depth = (-z - near) / (far - near)
        let mut view = [0.0f32; 16];
        for i in 0..4 {
            view[5 * i] = 1.0;
        }
        let vertex = |z: f32| [0.0, 0.0, z, 0.0, 1.0, 0.0];
        let vertices: Vec<f32> = [-3.0, -5.0, -2.0, -1.5].iter().flat_map(|&z| vertex(z)).collect();
        // near 1, far 5: depths 0.5, 1.0, 0.25, 0.125
        assert_eq!(caster_depth_floor(&vertices, Some(3), &view, 1.0, 5.0), Some(0.25));
        assert_eq!(caster_depth_floor(&vertices, None, &view, 1.0, 5.0), Some(0.125));
        assert_eq!(caster_depth_floor(&vertices, None, &view, 2.0, 5.0), Some(0.0));
        assert_eq!(caster_depth_floor(&vertices, Some(0), &view, 1.0, 5.0), None);
        assert_eq!(caster_depth_floor(&vertices, None, &view, 5.0, 5.0), None);
    }

    #[test]
    fn refuses_duplicate_texture_names() {
        let mut g = tiny();
        g.textures.push(g.textures[0].clone());
        let e = PassGraph::from_ron(&g.to_ron()).unwrap_err();
        assert_eq!(
            e,
            GraphError::Duplicate {
                what: "texture",
                name: "z".into()
            }
        );
    }

    #[test]
    fn refuses_duplicate_pass_names() {
        let e = changed("name: \"shade\",", "name: \"depth\",").unwrap_err();
        assert_eq!(
            e,
            GraphError::Duplicate {
                what: "pass",
                name: "depth".into()
            }
        );
        assert_eq!(e.to_string(), "two passes are named `depth`");
    }

    #[test]
    fn refuses_duplicate_param_names() {
        let mut g = tiny();
        let p = ParamDecl {
            name: "k".into(),
            ty: ParamType::I32,
            value: 1.0,
            range: None,
            offset: None,
            doc: None,
        };
        g.params = vec![p.clone(), p];
        let e = PassGraph::from_ron(&g.to_ron()).unwrap_err();
        assert_eq!(
            e,
            GraphError::Duplicate {
                what: "param",
                name: "k".into()
            }
        );
    }

    #[test]
    fn refuses_reading_an_unwritten_texture() {
        // The depth pass no longer writes `z`, which the shade pass reads.
        let mut g = tiny();
        g.textures.push(TextureDecl {
            name: "other".into(),
            ..g.textures[0].clone()
        });
        let text = valid_text().replacen("texture: \"z\",\n", "texture: \"other\",\n", 1);
        let e = PassGraph::from_ron(&text.replacen(
            "textures: [",
            &format!("textures: [{},", ron::to_string(&g.textures[1]).unwrap()),
            1,
        ))
        .unwrap_err();
        assert_eq!(
            e,
            GraphError::Unwritten {
                pass: "shade".into(),
                texture: "z".into()
            }
        );
        assert!(e.to_string().contains("pass `shade` reads texture `z`"), "{e}");
    }

    #[test]
    fn refuses_a_target_layer_outside_the_texture() {
        let e = changed("layer: 0,", "layer: 99,").unwrap_err();
        assert_eq!(
            e,
            GraphError::Layer {
                pass: "depth".into(),
                texture: "z".into(),
                layer: 99,
                layers: 1
            }
        );
        assert!(e.to_string().contains("pass `depth` writes layer 99"), "{e}");
    }

    #[test]
    fn refuses_zero_layers() {
        let e = changed("layers: 1,", "layers: 0,").unwrap_err();
        assert!(
            matches!(&e, GraphError::Texture { texture, field: "layers", .. } if texture == "z"),
            "{e}"
        );
        assert!(e.to_string().contains("texture `z`, field `layers`"), "{e}");
    }
}
