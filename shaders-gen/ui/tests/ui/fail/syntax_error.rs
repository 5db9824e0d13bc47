sshc_shaders_gen::technique!(mod broken = "tests/ui/fail/syntax_error.ron");

fn main() {}
