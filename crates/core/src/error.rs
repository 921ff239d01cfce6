//! Typed errors of the numerics; the layers above wrap them (`peritherm-io`'s and
//! `peritherm-post`'s `Error::Core`) and the CLI turns each into one line.

/// Everything that can go wrong in the numerics: a model, expression, time step, state or
/// linear solve that does not hold, or another rank that stopped.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A model that is inconsistent although each key was valid.
    #[error("{key}: {message}")]
    Model {
        /// The key or component that causes it.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// An expression string that does not parse or evaluate.
    #[error("expression `{expr}`: {message}")]
    Expr {
        /// The expression text.
        expr: String,
        /// The reason.
        message: String,
    },
    /// A time step above the stability bound of theory §4.
    #[error("{dt:.4e} s exceeds the stable bound {bound:.4e} s of the {integrator} integrator (theory §4); use a smaller time.dt or omit it")]
    UnstableDt {
        /// The requested step, s.
        dt: f64,
        /// The largest stable step, s.
        bound: f64,
        /// Integrator name.
        integrator: &'static str,
    },
    /// The state became non-finite during a run.
    #[error("temperature became non-finite at node {node} (t = {time:e} s); check conductivity, dt and boundary values")]
    NonFinite {
        /// First bad node (body index).
        node: usize,
        /// Simulation time, s.
        time: f64,
    },
    /// Another rank of a distributed run stopped; the first rank reports why.
    #[error("another rank of the distributed run stopped (rank 0 says why)")]
    Peer,
    /// A linear solve of the implicit or steady solvers failed (theory §4).
    #[error("linear solver: {message}")]
    Solver {
        /// What failed and why.
        message: String,
    },
}

/// Result alias of the numerics.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// Shorthand for a [`Error::Model`].
    pub fn model(key: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Model {
            key: key.into(),
            message: message.into(),
        }
    }
}
