//! Decoded-model mutation: the input is a list of edits on the parts of a small real model (see
//! `mutate_model.rs`); the edited model is written with a valid checksum, then loaded, reported by
//! `info`, animated in a crowd and synthesized as a walk. Any of these may refuse the model with an
//! error; none may panic.
#![no_main]

use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;

#[path = "../mutate_model.rs"]
mod mutate_model;

#[path = "../seed_model.rs"]
mod seed_model;

fn seed() -> &'static mutate_model::Seed {
    static SEED: OnceLock<mutate_model::Seed> = OnceLock::new();
    SEED.get_or_init(|| mutate_model::Seed::new(&seed_model::small_model()))
}

fuzz_target!(|data: &[u8]| {
    mutate_model::run(seed(), data);
});
