//! pfem-assembly
