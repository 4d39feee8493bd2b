//! Replays every committed fuzz input (`fuzz/corpus/<target>/` and the crashes and hangs found,
//! `fuzz/regressions/<target>/`) through the same target bodies as `cargo fuzz` (`fuzz/targets.rs`),
//! so that a new panic or broken round trip on a known input fails plain `cargo test`.
#![cfg(not(target_arch = "wasm32"))]

#[path = "../fuzz/targets.rs"]
mod targets;

use std::path::Path;
use std::time::{Duration, Instant};

/// The longest one input may take in a debug build (a hang found by the fuzzer must not come
/// back either; the fuzzers' own limit is 10 s in release).
const MAX_INPUT_TIME: Duration = Duration::from_secs(20);

fn replay(kind: &str) -> usize {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz")
        .join(kind);
    let mut count = 0;
    for (name, body) in targets::TARGETS {
        let dir = root.join(name);
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut files: Vec<_> = entries.filter_map(|e| e.ok()).map(|e| e.path()).collect();
        files.sort();
        for file in files.iter().filter(|f| f.is_file()) {
            let data = std::fs::read(file).unwrap();
            let start = Instant::now();
            let outcome = std::panic::catch_unwind(|| body(&data));
            assert!(outcome.is_ok(), "{name}: {} panics", file.display());
            let took = start.elapsed();
            assert!(
                took < MAX_INPUT_TIME,
                "{name}: {} took {took:?}",
                file.display()
            );
            count += 1;
        }
    }
    count
}

#[test]
fn corpus_replays_cleanly() {
    let n = replay("corpus");
    assert!(n >= targets::TARGETS.len(), "only {n} corpus files found");
}

#[test]
fn regressions_replay_cleanly() {
    replay("regressions");
}
