//! Files a graph names are read only if they are regular files below a size cap, with a
//! bounded reader: FIFOs, devices and huge (sparse) files are refused naming the path.

use sshc_runtime::gpu::{Gpu, MAX_GRAPH_BYTES, MAX_SHADER_BYTES, RuntimeError, Technique, read_capped};
use sshc_runtime::graph::*;

mod common;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

fn fresh_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sshc-files-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The one-pass graph of the other runtime tests, naming `t.depth.wgsl`, written to
/// `dir/t.graph.ron` (the shader file is left to each test).
fn write_graph(dir: &Path) -> PathBuf {
    let (g, _) = common::depth_graph(Views::LightCenter);
    let p = dir.join("t.graph.ron");
    std::fs::write(&p, g.to_ron()).unwrap();
    p
}

/// Run `f` on another thread; a hang (a FIFO read) fails the test after 20 s.
fn within_20s<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(Duration::from_secs(20)).expect("hung: a FIFO or device was read")
}

fn load_err(graph: PathBuf) -> RuntimeError {
    within_20s(move || {
        let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
        Technique::load(&gpu, &graph).expect_err("must be refused")
    })
}

#[test]
fn a_shader_that_is_a_fifo_is_refused() {
    let dir = fresh_dir("fifo");
    let graph = write_graph(&dir);
    let st = std::process::Command::new("mkfifo").arg(dir.join("t.depth.wgsl")).status().unwrap();
    assert!(st.success());
    let e = load_err(graph);
    assert!(
        matches!(&e, RuntimeError::File { path, message } if path.ends_with("t.depth.wgsl") && message.contains("not a regular file")),
        "{e}"
    );
    // and a graph file that is a FIFO
    let fifo = dir.join("f.graph.ron");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let e = within_20s(move || read_capped(&fifo, MAX_GRAPH_BYTES).unwrap_err());
    assert!(
        e.to_string().contains("f.graph.ron") && e.to_string().contains("not a regular file"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_sparse_shader_over_the_cap_is_refused_without_reading_it() {
    // A 3 GB sparse file: no disk used, and refused from its size (bound: under 20 s, no
    // allocation of its size).
    let dir = fresh_dir("sparse");
    let graph = write_graph(&dir);
    let f = std::fs::File::create(dir.join("t.depth.wgsl")).unwrap();
    f.set_len(3 << 30).unwrap();
    drop(f);
    let e = load_err(graph);
    let text = e.to_string();
    assert!(
        text.contains("t.depth.wgsl") && text.contains(&format!("limit of {MAX_SHADER_BYTES} bytes")),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_graph_linked_to_dev_zero_is_refused() {
    let dir = fresh_dir("zero");
    let link = dir.join("z.graph.ron");
    std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
    let e = load_err(link);
    assert!(
        matches!(&e, RuntimeError::File { path, message } if path.ends_with("z.graph.ron") && message.contains("not a regular file")),
        "{e}"
    );
    // A regular graph just over the cap is refused naming the limit.
    let big = dir.join("big.graph.ron");
    std::fs::File::create(&big).unwrap().set_len(MAX_GRAPH_BYTES + 1).unwrap();
    let e = read_capped(&big, MAX_GRAPH_BYTES).unwrap_err();
    assert!(e.to_string().contains(&format!("limit of {MAX_GRAPH_BYTES} bytes")), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
