//! Progress of the long parts of a set-up (the consistent weights' Newton solve), reported to
//! one process-wide sink that the front end sets (the command line draws it on a terminal);
//! without a sink a report costs one uncontended read lock. Numerics never draw: they report.

use crate::math::Real;
use std::sync::{Arc, RwLock};

/// One step of progress.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Event {
    /// The consistent weights are being solved for `nodes` nodes and `pairs` stored pairs.
    WeightsStart {
        /// Nodes whose moments are corrected.
        nodes: usize,
        /// Stored pair conductances (CSR entries).
        pairs: usize,
    },
    /// A Newton step of the weights begins.
    Newton {
        /// The step's number, from 1 (this solve).
        step: usize,
        /// Largest relative moment residual at its start.
        residual: Real,
        /// Conjugate-gradient iterations so far (this solve).
        iterations: usize,
    },
    /// The consistent weights were loaded from the cache instead of solved.
    WeightsLoaded,
}

/// A receiver of progress events.
pub type Sink = Arc<dyn Fn(&Event) + Send + Sync>;

static SINK: RwLock<Option<Sink>> = RwLock::new(None);

/// Sends every later event to `sink` (None: nowhere).
pub fn set_sink(sink: Option<Sink>) {
    *SINK.write().unwrap_or_else(|e| e.into_inner()) = sink;
}

/// Reports `event` to the sink, if there is one.
pub fn report(event: Event) {
    let sink = SINK.read().unwrap_or_else(|e| e.into_inner()).clone();
    if let Some(sink) = sink {
        sink(&event);
    }
}
