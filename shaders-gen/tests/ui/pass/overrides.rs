// Overrides as `sshc --set` / `--precision`, attributes on the module, and the graph
// schema crate named through another path (as seen from inside the generated module).
mod rt {
    pub use sshc_graph;
}

sshc_shaders_gen::technique!(
    /// PCF over 5 x 5 taps, the depth at half precision.
    #[allow(unused)]
    pub(crate) mod pcf5 = "../techniques/pcf.ron",
    set: { N = 5, bias = 0.001, "slope_bias" = 2 },
    precision: { z = F16 },
    graph: crate::rt::sshc_graph,
);

fn main() {
    assert_eq!(pcf5::fixed::N, 5);
    let p = pcf5::Params::default();
    assert_eq!((p.bias, p.slope_bias), (0.001, 2.0));
    let g = pcf5::graph().unwrap();
    assert!(g.textures.iter().any(|t| format!("{:?}", t.format) == "R16Float"));
}
