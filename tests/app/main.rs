//! The browser app's core (`wslap::app`): loading files without losing data, settings, the
//! three run kinds, z_s redraws, views, hover read-outs, downloads and project files, and the
//! bad inputs the app passes to the core in memory. These are the paths the web worker uses;
//! they run natively and in a dedicated worker.

#[path = "../common/mod.rs"]
mod common;
mod fixtures;

mod bad_inputs;
mod ensemble;
mod iterates;
mod loading;
mod model;
mod observe;
mod projects;
mod runs;
mod views;
