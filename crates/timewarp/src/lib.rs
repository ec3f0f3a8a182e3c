//! Dynamic time warping and the incremental inverse timewarp.
//!
//! This crate is for: aligning many frame sequences to a reference at a fixed number of frames, and
//! playing an aligned sequence back at any frame rate through its time-increment channel. It works on
//! plain feature and value sequences. It is not for: reading motion files or computing pose features
//! (see `motion-io`).
