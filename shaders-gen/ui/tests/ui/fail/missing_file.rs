sshc_shaders_gen::technique!(mod missing = "techniques/no_such_technique.ron");

fn main() {}
