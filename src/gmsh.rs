//! Reading gmsh MSH 4.1 files (ASCII and binary) into a [`crate::mesh::Mesh`].
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use std::path::Path;

/// Placeholder until the reader lands.
pub fn read(path: &Path) -> Result<Mesh> {
    Err(Error::Mesh {
        path: path.to_path_buf(),
        message: "reader not yet available".into(),
    })
}
