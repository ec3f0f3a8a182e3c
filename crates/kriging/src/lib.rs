//! Geostatistical interpolation of vector-valued samples over a parameter space.
//!
//! This crate is for: empirical and theoretical variograms, ordinary and universal kriging (Mukai and
//! Kuriyama eq. 8 and appendix A), leave-one-out cross validation and an RBF baseline, for any values,
//! not only motion. It is not for: tensors or motion data themselves.
