// Every bundled technique embeds; its Params is filled and turned into uniform bytes.
sshc_shaders_gen::technique!(pub mod hard = "../techniques/hard.ron");
sshc_shaders_gen::technique!(pub mod pcf = "../techniques/pcf.ron");
sshc_shaders_gen::technique!(pub mod vsm = "../techniques/vsm.ron");
sshc_shaders_gen::technique!(pub mod esm = "../techniques/esm.ron");
sshc_shaders_gen::technique!(pub mod csm = "../techniques/csm.ron");

fn check(graph: sshc_graph::PassGraph, bytes: &[u8], shaders: &[(&str, &str)]) {
    assert_eq!(graph.params_size as usize, bytes.len());
    assert_eq!(graph.passes.len(), shaders.len());
}

fn main() {
    let h = hard::Params { bias: 0.001, ..Default::default() };
    check(hard::graph().unwrap(), &h.to_bytes(), hard::SHADERS);
    let p = pcf::Params { slope_bias: 2.0, ..Default::default() };
    check(pcf::graph().unwrap(), &p.to_bytes(), pcf::SHADERS);
    let mut v = vsm::Params::default();
    v.bleed = 0.3;
    check(vsm::graph().unwrap(), &v.to_bytes(), vsm::SHADERS);
    let e = esm::Params { eps: 0.1, ..Default::default() };
    check(esm::graph().unwrap(), &e.to_bytes(), esm::SHADERS);
    let c = csm::Params::default();
    check(csm::graph().unwrap(), &c.to_bytes(), csm::SHADERS);
    let _: i32 = pcf::fixed::N;
    let _: f32 = esm::fixed::c;
    assert_eq!(std::mem::size_of::<pcf::Params>(), pcf::PARAMS_SIZE as usize);
}
