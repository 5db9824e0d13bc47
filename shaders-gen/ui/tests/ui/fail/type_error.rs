sshc_shaders_gen::technique!(mod typed = "tests/ui/fail/type_error.ron");

fn main() {}
