//! The embedded modules hold exactly what the compiler library returns for the same
//! technique and options, and `Params` writes the uniform the runtime would write from the
//! graph's defaults. (No GPU: `gpu.rs` renders.)

use sshc_graph::PassGraph;

sshc_shaders_gen::technique!(mod hard = "../techniques/hard.ron");
sshc_shaders_gen::technique!(mod pcf = "../techniques/pcf.ron");
sshc_shaders_gen::technique!(mod vsm = "../techniques/vsm.ron");
sshc_shaders_gen::technique!(mod esm = "../techniques/esm.ron");
sshc_shaders_gen::technique!(mod csm = "../techniques/csm.ron");
// functions of the technique and four moments
sshc_shaders_gen::technique!(mod evsm = "../techniques/evsm.ron");
sshc_shaders_gen::technique!(mod msm = "../techniques/msm.ron");
sshc_shaders_gen::technique!(
    /// PCF over 5 x 5 taps.
    pub(crate) mod pcf5 = "../techniques/pcf.ron",
    set: { N = 5 },
);
sshc_shaders_gen::technique!(mod no_runtime_params = "tests/techniques/no_runtime_params.ron");
sshc_shaders_gen::technique!(mod typed_params = "tests/techniques/typed_params.ron");
sshc_shaders_gen::technique!(mod unused_params = "tests/techniques/unused_params.ron");
// what `sshc tune` writes (docs/tune/acne/tuned.ron): chosen defaults, `shadow_map:` and a
// `tune:` block
sshc_shaders_gen::technique!(mod tuned_pcf = "tests/techniques/tuned_pcf.ron");
sshc_shaders_gen::technique!(mod esm_f16 = "../techniques/esm.ron", set: { "c" = 10.0 }, precision: { e = "F16" }, graph: ::sshc_graph);

// Attributes and visibility on the module, overrides by name and by string as `sshc --set`
// and `--precision` take them, and the graph schema crate named through another path, as
// seen from inside the generated module.
mod rt {
    pub use sshc_graph;
}
sshc_shaders_gen::technique!(
    /// PCF over 5 x 5 taps, the depth at half precision.
    #[allow(unused)]
    pub(crate) mod pcf5_f16 = "../techniques/pcf.ron",
    set: { N = 5, bias = 0.001, "slope_bias" = 2 },
    precision: { z = F16 },
    graph: crate::rt::sshc_graph,
);

struct Embedded {
    technique: &'static str,
    graph_ron: &'static str,
    shaders: &'static [(&'static str, &'static str)],
    graph: PassGraph,
    params: Vec<u8>,
}

macro_rules! embedded {
    ($m:ident) => {
        Embedded {
            technique: $m::TECHNIQUE,
            graph_ron: $m::GRAPH_RON,
            shaders: $m::SHADERS,
            graph: $m::graph().expect("the embedded graph parses"),
            params: $m::Params::default().to_bytes().to_vec(),
        }
    };
}

fn compile(file: &str, set: &[(&str, &str)], precision: &[(&str, &str)]) -> sshc::Compiled {
    let dir = if file.contains('/') { "." } else { "../techniques" };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(dir).join(file);
    let src = std::fs::read_to_string(&path).unwrap();
    let pairs = |v: &[(&str, &str)]| v.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
    let opts = sshc::CompileOptions {
        set: pairs(set),
        precision: pairs(precision),
        ..Default::default()
    };
    sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render(file, &src)))
}

#[test]
fn embedded_modules_equal_the_compiler_output() {
    let cases = [
        (embedded!(hard), compile("hard.ron", &[], &[])),
        (embedded!(pcf), compile("pcf.ron", &[], &[])),
        (embedded!(vsm), compile("vsm.ron", &[], &[])),
        (embedded!(esm), compile("esm.ron", &[], &[])),
        (embedded!(csm), compile("csm.ron", &[], &[])),
        (embedded!(evsm), compile("evsm.ron", &[], &[])),
        (embedded!(msm), compile("msm.ron", &[], &[])),
        (embedded!(pcf5), compile("pcf.ron", &[("N", "5")], &[])),
        (embedded!(esm_f16), compile("esm.ron", &[("c", "10.0")], &[("e", "F16")])),
        (
            embedded!(no_runtime_params),
            compile("tests/techniques/no_runtime_params.ron", &[], &[]),
        ),
        (embedded!(typed_params), compile("tests/techniques/typed_params.ron", &[], &[])),
        (embedded!(unused_params), compile("tests/techniques/unused_params.ron", &[], &[])),
        (embedded!(tuned_pcf), compile("tests/techniques/tuned_pcf.ron", &[], &[])),
    ];
    // a tuned file's map size reaches the embedded graph
    assert_eq!(embedded!(tuned_pcf).graph.shadow_map, Some(256));
    for (e, c) in cases {
        assert_eq!(e.technique, c.graph.technique);
        assert_eq!(e.graph, c.graph, "{}", e.technique);
        assert_eq!(e.graph_ron, c.graph.to_ron(), "{}", e.technique);
        let shaders: Vec<(String, String)> = e.shaders.iter().map(|(f, s)| (f.to_string(), s.to_string())).collect();
        assert_eq!(shaders, c.shaders, "{}", e.technique);
        assert_eq!(e.params.len(), c.graph.params_size as usize, "{}", e.technique);
        // the macro lays the bytes out itself; the runtime binds the schema's layout
        assert_eq!(e.params, c.graph.default_params(), "{}", e.technique);
    }
}

#[test]
fn params_fields_follow_the_technique() {
    // Runtime params are fields (with the technique's defaults), fixed ones constants.
    let p = pcf::Params::default();
    assert_eq!((p.bias, p.slope_bias), (0.0005, 1.5));
    assert_eq!(pcf::Params::NAMES, ["bias", "slope_bias"]);
    assert_eq!(pcf::Params::SIZE, 16);
    assert_eq!(std::mem::size_of::<pcf::Params>(), 16);
    assert_eq!(pcf::fixed::N, 3);
    assert_eq!(pcf5::fixed::N, 5);
    assert_eq!(csm::fixed::M, 4);
    assert_eq!(esm_f16::fixed::c, 10.0);

    let q = pcf::Params {
        slope_bias: 2.0,
        ..Default::default()
    };
    let b = q.to_bytes();
    assert_eq!(b[0..4], 0.0005f32.to_le_bytes());
    assert_eq!(b[4..8], 2.0f32.to_le_bytes());
    assert_eq!(b[8..16], [0; 8]);
    assert_eq!(q.values(), [("bias", 0.0005f32 as f64), ("slope_bias", 2.0)]);

    let e = esm::Params::default();
    assert_eq!((e.eps, e.zmax_offset, e.bias), (0.05, 0.01, 0.0));
    assert!(esm::WARNINGS.is_empty());
    assert!(pcf::SOURCE.contains("Percentage-closer filtering"));
    assert!(pcf::SHADE_WGSL.contains("struct Params"));
    assert_eq!(pcf::SHADERS.len(), 2);
}

#[test]
fn params_of_every_type_and_none() {
    // No runtime param: an empty Params, no uniform; fixed params keep their types.
    assert_eq!(no_runtime_params::Params::SIZE, 0);
    assert_eq!(no_runtime_params::Params::default().to_bytes(), [0u8; 0]);
    assert_eq!(no_runtime_params::PARAMS_SIZE, 0);
    const { assert!(no_runtime_params::fixed::soft) };
    assert_eq!(no_runtime_params::fixed::bias, 0.001);

    // i32, Bool as u32, f32; keyword names become raw identifiers.
    let p = typed_params::Params::default();
    assert_eq!((p.r#dyn, p.r#gen, p.bias), (-2, 1, 0.25));
    let b = typed_params::Params {
        r#gen: 0,
        ..Default::default()
    }
    .to_bytes();
    assert_eq!(b.len(), 16);
    assert_eq!(b[0..4], (-2i32).to_le_bytes());
    assert_eq!(b[4..8], 0u32.to_le_bytes());
    assert_eq!(b[8..12], 0.25f32.to_le_bytes());
    assert_eq!(typed_params::Params::NAMES, ["dyn", "gen", "bias"]);

    // Params no shader reads: no module declares the struct, the uniform is still bound.
    assert!(unused_params::SHADERS.iter().all(|(_, s)| !s.contains("struct Params")));
    assert_eq!(unused_params::Params::SIZE, 16);
    assert_eq!(
        unused_params::Params::default().to_bytes(),
        typed_params::Params::default().to_bytes()
    );
}

/// A host's use of the modules: `Params` filled by field name and turned into uniform
/// bytes of the graph's size, one shader per pass, the fixed values typed as the technique
/// declares them.
#[test]
fn params_fill_by_field_and_fixed_values_are_typed() {
    fn check(graph: PassGraph, bytes: &[u8], shaders: &[(&str, &str)]) {
        assert_eq!(graph.params_size as usize, bytes.len());
        assert_eq!(graph.passes.len(), shaders.len());
    }
    let h = hard::Params {
        bias: 0.001,
        ..Default::default()
    };
    check(hard::graph().unwrap(), &h.to_bytes(), hard::SHADERS);
    let p = pcf::Params {
        slope_bias: 2.0,
        ..Default::default()
    };
    check(pcf::graph().unwrap(), &p.to_bytes(), pcf::SHADERS);
    let v = vsm::Params {
        bleed: 0.3,
        ..Default::default()
    };
    check(vsm::graph().unwrap(), &v.to_bytes(), vsm::SHADERS);
    let e = esm::Params {
        eps: 0.1,
        ..Default::default()
    };
    check(esm::graph().unwrap(), &e.to_bytes(), esm::SHADERS);
    let c = csm::Params::default();
    check(csm::graph().unwrap(), &c.to_bytes(), csm::SHADERS);
    let n: i32 = pcf::fixed::N;
    let k: f32 = esm::fixed::c;
    assert_eq!((n, k), (3, 80.0));
    assert_eq!(std::mem::size_of::<pcf::Params>(), pcf::PARAMS_SIZE as usize);
}

#[test]
fn overrides_reach_the_fixed_values_the_defaults_and_the_formats() {
    assert_eq!(pcf5_f16::fixed::N, 5);
    let p = pcf5_f16::Params::default();
    assert_eq!((p.bias, p.slope_bias), (0.001, 2.0));
    let g = pcf5_f16::graph().unwrap();
    assert!(g.textures.iter().any(|t| format!("{:?}", t.format) == "R16Float"));
}
