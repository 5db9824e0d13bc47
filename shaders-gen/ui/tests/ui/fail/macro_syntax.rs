// No `mod` keyword; then an unknown option.
sshc_shaders_gen::technique!(pub pcf = "../techniques/pcf.ron");
sshc_shaders_gen::technique!(mod pcf = "../techniques/pcf.ron", sets: { N = 5 });

fn main() {}
