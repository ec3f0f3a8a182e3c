//! Crowds of walking characters over a field.
//!
//! This crate is for: walkers with paths, clip scheduling and transitions, a camera with frustum
//! culling over a bounding volume hierarchy, parallel per-frame updates, timings and PNG rendering.
//! It knows nothing of tensors: clips come from a `ClipSource` implementation. It is not for:
//! synthesising motion itself.
