//! [`RuntimeError`]: every way the runtime refuses or fails, as a value.

use crate::graph;
use std::fmt;
use std::path::PathBuf;

/// Why the runtime could not do what was asked.
#[derive(Clone, Debug, PartialEq)]
pub enum RuntimeError {
    /// No GPU adapter: the message names what to install.
    NoAdapter(String),
    Device(String),
    Graph(graph::GraphError),
    /// A file named by the graph could not be read, or lies outside the graph's folder.
    File {
        path: PathBuf,
        message: String,
    },
    /// A shader module of the graph does not validate.
    Shader {
        file: String,
        message: String,
    },
    /// A resource exceeds the device's limits.
    Limit {
        what: String,
        needed: u64,
        limit: u64,
    },
    /// wgpu refused an object or a command.
    Wgpu {
        context: String,
        message: String,
    },
    /// The graph asks for something this runtime cannot do yet; it is refused rather than
    /// run another way.
    Unsupported {
        pass: String,
        feature: String,
    },
    /// A pass wrote values outside what its output may hold (non-finite, or visibility
    /// outside [0, 1]); they are never passed on.
    Output {
        pass: String,
        message: String,
    },
    Param(String),
    NotFound(String),
    /// The device lacks features or limits the graph needs: one line each, naming the
    /// feature or limit and the pass that needs it ([`crate::gpu::Requirements`]).
    Unsatisfied {
        technique: String,
        missing: Vec<String>,
    },
}

impl fmt::Display for RuntimeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RuntimeError::NoAdapter(m) => write!(f, "no GPU adapter: {m}"),
            RuntimeError::Device(m) => write!(f, "cannot open the GPU device: {m}"),
            RuntimeError::Graph(e) => write!(f, "{e}"),
            RuntimeError::File { path, message } => write!(f, "{}: {message}", path.display()),
            RuntimeError::Shader { file, message } => write!(f, "shader `{file}` does not validate:\n{message}"),
            RuntimeError::Limit { what, needed, limit } => write!(f, "{what} needs {needed}, above the device's limit of {limit}"),
            RuntimeError::Wgpu { context, message } => write!(f, "{context}: {message}"),
            RuntimeError::Unsupported { pass, feature } => {
                write!(f, "pass `{pass}` needs {feature}, which this runtime does not support yet")
            }
            RuntimeError::Output { pass, message } => write!(f, "pass `{pass}` wrote {message}"),
            RuntimeError::Param(m) => write!(f, "{m}"),
            RuntimeError::NotFound(m) => write!(f, "{m}"),
            RuntimeError::Unsatisfied { technique, missing } => {
                write!(f, "technique `{technique}` cannot run on this device, which lacks:")?;
                for m in missing {
                    write!(f, "\n  - {m}")?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for RuntimeError {}

pub type Result<T> = std::result::Result<T, RuntimeError>;

impl From<graph::GraphError> for RuntimeError {
    fn from(e: graph::GraphError) -> Self {
        RuntimeError::Graph(e)
    }
}

/// What a call that needs a binding says before one: every way of binding is named (a
/// host that binds with `bind_geometry` was told to call `bind_scene`; issue 49).
pub(crate) const NOTHING_BOUND: &str = "nothing is bound: bind a scene first (bind_scene, bind_geometry, bind_lights or bind_cascades)";
