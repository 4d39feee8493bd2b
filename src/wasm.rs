//! The one place that talks to JavaScript (compiled for wasm32 only).
