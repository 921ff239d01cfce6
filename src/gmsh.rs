//! Reading gmsh MSH 4.1 files (ASCII and binary) into a [`crate::mesh::Mesh`].
