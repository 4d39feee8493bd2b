//! `AppSession`: the app's [`Session`] as a JavaScript class living in the web worker.
//! Every method is a thin conversion; the work and the error messages are the core's.

use wasm_bindgen::prelude::*;

use crate::app::{AppError, DataRole, RunKind, Session, ViewOptions};
use crate::reconstruct::ConvergenceRecord;
use crate::solver::Control;

use super::{set, to_js};

/// Least time between two progress messages, in ms.
const PROGRESS_INTERVAL_MS: f64 = 100.0;

/// Passes QADP reports on to a JavaScript callback at most every [`PROGRESS_INTERVAL_MS`], with
/// `elapsed_ms` and any extra fields.
struct Throttle<'a> {
    progress: &'a js_sys::Function,
    clock: crate::products::Clock,
    last: f64,
}

impl<'a> Throttle<'a> {
    fn new(progress: &'a js_sys::Function) -> Self {
        Self {
            progress,
            clock: crate::products::Clock::start(),
            last: f64::NEG_INFINITY,
        }
    }

    fn report(&mut self, r: &ConvergenceRecord, extra: &[(&str, f64)]) {
        let now = self.clock.ms();
        if now - self.last < PROGRESS_INTERVAL_MS {
            return;
        }
        self.last = now;
        if let Ok(v) = to_js(r) {
            if let Some(obj) = v.dyn_ref::<js_sys::Object>() {
                let _ = set(obj, "elapsed_ms", &JsValue::from_f64(now));
                for (key, value) in extra {
                    let _ = set(obj, key, &JsValue::from_f64(*value));
                }
            }
            let _ = self.progress.call1(&JsValue::NULL, &v);
        }
    }
}

/// The core's progress callback for a method of the worker: each report goes on to `progress`
/// through a new [`Throttle`], with the fields `extra`; it never cancels (a Cancel ends the
/// worker).
pub(super) fn reporter<'a, const N: usize>(
    progress: &'a js_sys::Function,
    extra: [(&'static str, f64); N],
) -> impl FnMut(&ConvergenceRecord) -> Control + 'a {
    let mut throttle = Throttle::new(progress);
    move |r: &ConvergenceRecord| {
        throttle.report(r, &extra);
        Control::Continue
    }
}

pub(super) fn err(e: impl std::fmt::Display) -> JsError {
    JsError::new(&e.to_string())
}

/// An `Error` with the core's message and, when the error has one, its [`AppError::code`] as
/// the property `code` (the worker passes it on; the page tells kinds apart by it).
fn coded(e: AppError) -> JsValue {
    let error = js_sys::Error::new(&e.to_string());
    if let Some(code) = e.code() {
        // Setting a property on a fresh Error cannot fail.
        let _ = js_sys::Reflect::set(&error, &"code".into(), &code.into());
    }
    error.into()
}

fn view_options(options: JsValue) -> Result<ViewOptions, JsError> {
    if options.is_undefined() || options.is_null() {
        return Ok(ViewOptions::default());
    }
    serde_wasm_bindgen::from_value(options).map_err(|e| JsError::new(&format!("view options: {e}")))
}

fn bytes(png: &[u8]) -> JsValue {
    js_sys::Uint8Array::from(png).into()
}

/// Files as an array of `{name, bytes}`.
pub(super) fn files_js<'a>(
    files: impl Iterator<Item = (&'a str, &'a [u8])>,
) -> Result<JsValue, JsError> {
    let out = js_sys::Array::new();
    for (name, data) in files {
        let obj = js_sys::Object::new();
        set(&obj, "name", &JsValue::from_str(name))?;
        set(&obj, "bytes", &bytes(data))?;
        out.push(&obj);
    }
    Ok(out.into())
}

/// One session: loaded data, settings and the last result.
#[wasm_bindgen]
pub struct AppSession {
    pub(super) inner: Session,
    /// The files of the last cross-validation's convergence maps (see
    /// [`Session::crossval_files`]).
    crossval_files: Vec<(&'static str, Vec<u8>)>,
    /// The last cross-validation, for the verdict that counts it ([`Self::verdict`]).
    crossval: Option<crate::reconstruct::CrossValidation>,
    /// The ensemble members handed over so far (see `super::ensemble`).
    pub(super) ensemble_runs: Vec<super::ensemble::HandedMember>,
}

impl Default for AppSession {
    fn default() -> Self {
        Self::new()
    }
}

#[wasm_bindgen]
impl AppSession {
    /// An empty session with the app's default settings.
    #[wasm_bindgen(constructor)]
    pub fn new() -> AppSession {
        super::keep_panic_messages();
        AppSession {
            inner: Session::new(),
            crossval_files: Vec::new(),
            crossval: None,
            ensemble_runs: Vec::new(),
        }
    }

    /// Panics inside the core while the session is in use, as a bug would: for the page's
    /// test that a failure of the core is reported and the session rebuilt with its data
    /// (`tests/e2e/recovery.test.mjs`, through the worker's `?test-panic=JOB`). Nothing else
    /// calls it.
    pub fn fail_for_test(&mut self) {
        panic!("the failure a test asked for");
    }

    /// Sets the name shown in titles (an example or project name).
    pub fn set_name(&mut self, name: &str) {
        self.inner.name = name.to_string();
    }

    /// Loads a text file as `role` (images, members, arcs, shear, model); returns its
    /// `LoadReport`.
    /// On an error (naming the file, line and reason) nothing loaded changes; a file that
    /// wants a `.par` first is refused with `code` `"wants-par"`.
    pub fn load_text(&mut self, role: &str, name: &str, text: &str) -> Result<JsValue, JsValue> {
        let role = DataRole::parse(role).map_err(coded)?;
        let report = self.inner.load_text(role, name, text).map_err(coded)?;
        Ok(to_js(&report)?)
    }

    /// Checks the loaded file of `role` again with the current settings: its `LoadReport`, or
    /// `null` when none is loaded.
    pub fn reload(&mut self, role: &str) -> Result<JsValue, JsError> {
        let role = DataRole::parse(role).map_err(err)?;
        to_js(&self.inner.reload(role).map_err(err)?)
    }

    /// Fits the commented-out rows on `lines` (1-based) of the loaded member catalogue: its
    /// `LoadReport`. An error leaves the catalogue as it was.
    pub fn uncomment_members(&mut self, lines: Vec<u32>) -> Result<JsValue, JsError> {
        let lines: Vec<usize> = lines.into_iter().map(|l| l as usize).collect();
        to_js(&self.inner.uncomment_members(&lines).map_err(err)?)
    }

    /// Forgets the last result (its maps were made from data that have been replaced).
    pub fn clear_result(&mut self) {
        self.inner.result = None;
    }

    /// Forgets the file of `role`.
    pub fn clear(&mut self, role: &str) -> Result<(), JsError> {
        self.inner.data.clear(DataRole::parse(role).map_err(err)?);
        Ok(())
    }

    /// Loads a deflection FITS map for `axis` 0 (x) or 1 (y).
    pub fn load_fits(&mut self, axis: usize, name: &str, data: &[u8]) -> Result<JsValue, JsError> {
        to_js(&self.inner.load_fits(axis, name, data).map_err(err)?)
    }

    /// The settings (`AppSettings` as JSON-compatible object).
    pub fn settings(&self) -> Result<JsValue, JsError> {
        to_js(&self.inner.settings)
    }

    /// Sets the setting at `path` (e.g. `reconstruct.grid.cells`) to `value`; on an error the old
    /// value stays. Returns the settings.
    pub fn set_field(&mut self, path: &str, value: JsValue) -> Result<JsValue, JsError> {
        let value: serde_json::Value = serde_wasm_bindgen::from_value(value)
            .map_err(|e| JsError::new(&format!("{path}: {e}")))?;
        self.inner.set_field(path, value).map_err(err)?;
        self.settings()
    }

    /// Runs `kind` (reconstruct, forward, lookup). `progress` receives
    /// `{level, iteration, objective, grid_mass_msun, c, elapsed_ms}` at most every 100 ms.
    /// Returns `{kind, elapsed_ms, status, summary}`.
    pub fn run(&mut self, kind: &str, progress: &js_sys::Function) -> Result<JsValue, JsError> {
        let kind: RunKind = serde_json::from_value(serde_json::Value::String(kind.into()))
            .map_err(|_| JsError::new(&format!("unknown run kind '{kind}'")))?;
        let mut report = reporter(progress, []);
        self.inner.run(kind, &mut report).map_err(err)?;
        self.result_info()
    }

    /// For an "auto" regulariser strength, `{candidates, folds}` (each candidate is
    /// cross-validated over `folds` folds by [`AppSession::strength_trial`], one web worker per
    /// candidate, then [`AppSession::run_with_trials`] reconstructs); `null` when the strength
    /// is a number or too few systems can be held out (then [`AppSession::run`] does it all).
    pub fn strength_plan(&self) -> Result<JsValue, JsError> {
        match self.inner.strength_plan().map_err(err)? {
            Some((candidates, folds)) if folds >= 2 => {
                to_js(&serde_json::json!({"candidates": candidates, "folds": folds}))
            }
            _ => Ok(JsValue::NULL),
        }
    }

    /// The cross-validation of one candidate of the plan, `{regulariser, strength, cells}`
    /// (`cells` optional: the settings' grid; or a bare strength with the settings' regulariser
    /// and grid): a row of `strength_choice`, `{regulariser, strength, cells, holdout_median_arcsec, holdout_rms_arcsec, holdout_unmatched,
    /// fit_median_arcsec, holdout_by_system}`. `progress` gets the reports as [`AppSession::run`]'s, with
    /// `strength`. The session's result is not touched.
    pub fn strength_trial(
        &self,
        candidate: JsValue,
        folds: usize,
        estimates: JsValue,
        progress: &js_sys::Function,
    ) -> Result<JsValue, JsError> {
        #[derive(serde::Deserialize)]
        #[serde(untagged)]
        enum Given {
            Strength(f64),
            Candidate(crate::reconstruct::Candidate),
        }
        let given: Given = serde_wasm_bindgen::from_value(candidate)
            .map_err(|e| JsError::new(&format!("candidate: {e}")))?;
        let candidate = match given {
            Given::Strength(strength) => crate::reconstruct::Candidate {
                regulariser: self.inner.settings.reconstruct.objective.regulariser,
                strength,
                cells: None,
            },
            Given::Candidate(c) => c,
        };
        let mut report = reporter(progress, [("strength", candidate.strength)]);
        let estimates: Option<crate::reconstruct::EstimatedRedshifts> =
            serde_wasm_bindgen::from_value(estimates)
                .map_err(|e| JsError::new(&format!("estimates: {e}")))?;
        let row = self
            .inner
            .strength_trial(&candidate, folds, estimates.as_ref(), &mut report)
            .map_err(err)?;
        to_js(&row)
    }

    /// The second round the result's "auto" choice needs (it estimated redshifts after
    /// choosing): `{candidates, folds, estimates}`, each candidate to be tried by
    /// [`AppSession::strength_trial`] with `estimates`, then
    /// [`AppSession::choose_again_with_trials`]; `null` when it needs none.
    pub fn second_strength_round(&self) -> Result<JsValue, JsError> {
        match self.inner.second_strength_round() {
            Some(round) => to_js(&round),
            None => Ok(JsValue::NULL),
        }
    }

    /// The result's "auto" choice made again from the second round's `trials` (rows of
    /// [`AppSession::strength_trial`]): the map is fitted again only when the choice changes;
    /// as [`AppSession::run`] otherwise.
    pub fn choose_again_with_trials(
        &mut self,
        trials: JsValue,
        progress: &js_sys::Function,
    ) -> Result<JsValue, JsError> {
        let trials = trials_of(trials)?;
        let mut report = reporter(progress, []);
        self.inner
            .choose_again_with_trials(trials, &mut report)
            .map_err(err)?;
        self.result_info()
    }

    /// The reconstruction with the strength chosen from `trials` (the rows of
    /// [`AppSession::strength_trial`], one per candidate, over `folds` folds); as
    /// [`AppSession::run`] otherwise.
    pub fn run_with_trials(
        &mut self,
        trials: JsValue,
        folds: usize,
        progress: &js_sys::Function,
    ) -> Result<JsValue, JsError> {
        let trials = trials_of(trials)?;
        let mut report = reporter(progress, []);
        self.inner
            .run_with_trials(trials, folds, &mut report)
            .map_err(err)?;
        self.result_info()
    }

    /// K-fold cross-validation of the settings on the loaded data
    /// ([`Session::cross_validate`], default folds): `crossval.json` as an object. The
    /// session's result is not touched. `progress` gets each QADP report throttled like
    /// [`AppSession::run`]'s, with `fold` (1-based), `folds` and `elapsed_ms`.
    pub fn cross_validate(&mut self, progress: &js_sys::Function) -> Result<JsValue, JsError> {
        let folds = self.inner.default_folds().map_err(err)?;
        let mut throttle = Throttle::new(progress);
        let mut report = |fold: usize, r: &ConvergenceRecord| {
            throttle.report(r, &[("fold", fold as f64), ("folds", folds as f64)]);
            Control::Continue
        };
        let cv = self.inner.cross_validate(folds, &mut report).map_err(err)?;
        self.crossval_files = self.inner.crossval_files(&cv).map_err(err)?;
        let out = to_js(&cv);
        self.crossval = Some(cv);
        out
    }

    /// The verdict on the last result (`summary.json`'s `verdict`) counting the last
    /// cross-validation's held-out images ([`Session::verdict_after`]; the result's own
    /// verdict when none ran); null when the result is no reconstruction. The page asks for
    /// it only while that cross-validation is on screen.
    pub fn verdict(&self) -> Result<JsValue, JsError> {
        let cv = self.crossval.as_ref();
        match self.inner.verdict_after(cv).map_err(err)? {
            Some(v) => to_js(&v),
            None => Ok(JsValue::NULL),
        }
    }

    /// The last cross-validation's convergence maps as files: an array of `{name, bytes}`
    /// (`crossval-kappa-mean.fits`, `crossval-kappa-spread.fits`,
    /// `crossval-kappa-spread.png`).
    pub fn crossval_files(&self) -> Result<JsValue, JsError> {
        files_js(self.crossval_files.iter().map(|(n, b)| (*n, b.as_slice())))
    }

    /// `{kind, elapsed_ms, status, iterations, summary, model_note, main_curve_arcsec,
    /// model_galaxies}` of the last result (`model_note`: what the caption says of the loaded
    /// model file, [`crate::app::Session::model_note`], or null; `main_curve_arcsec`: the main
    /// curve's Einstein radius when the caption gives it,
    /// `Summary::main_curve_apart_arcsec` of the products, or null).
    pub fn result_info(&self) -> Result<JsValue, JsError> {
        let r = self.inner.result().map_err(err)?;
        let summary: serde_json::Value =
            serde_json::from_str(&r.summary_json().map_err(err)?).map_err(err)?;
        let rec = r.reconstruction();
        to_js(&serde_json::json!({
            "kind": r.kind,
            "elapsed_ms": r.elapsed_ms,
            "status": rec.map(|x| x.status.name()),
            "iterations": rec.map(|x| x.iterations),
            "summary": summary,
            "model_note": self.inner.model_note(r),
            "main_curve_arcsec": r.products().summary().main_curve_apart_arcsec(),
            // What the verdict may offer to fit: `[{id, line, mag, mag_from_mass}]` of the
            // loaded .par (`mag_from_mass`: the .par wrote no `mag`, see `ModelGalaxy`).
            "model_galaxies": self.inner.model_galaxies().iter()
                .map(|g| serde_json::json!({
                    "id": g.member.id,
                    "line": g.member.line,
                    "mag": g.member.mag,
                    "mag_from_mass": g.mag_from_mass,
                }))
                .collect::<Vec<_>>(),
        }))
    }

    /// The iterates the last reconstruction kept, to step through with the view option
    /// `iterate: k`: `{iterations, method, steps: [{iteration, objective}]}`, or `null` (no
    /// reconstruction, or none kept: a restored project).
    pub fn iterates(&self) -> Result<JsValue, JsError> {
        let r = self.inner.result().map_err(err)?;
        match r.iterate_list() {
            Some(list) => to_js(&list),
            None => Ok(JsValue::NULL),
        }
    }

    /// Sets the source redshift and redraws the curves from the stored maps (no new solve).
    pub fn set_z_source(&mut self, z_source: f64) -> Result<JsValue, JsError> {
        self.inner.set_z_source(z_source).map_err(err)?;
        self.settings()
    }

    /// One view as PNG bytes: `kappa`, `source`, `data`, `radial`, `convergence`, `compare`
    /// or `spread` (the ensemble's).
    /// The option `iterate: k` draws the mass map of the `k`-th kept iterate
    /// ([`AppSession::iterates`]).
    pub fn view(&self, name: &str, options: JsValue) -> Result<JsValue, JsError> {
        let opts = view_options(options)?;
        let s = &self.inner;
        let v = match name {
            "kappa" => s.kappa_view(&opts),
            "source" => s.source_view(&opts),
            "data" => s.data_view(&opts),
            "radial" => s.radial_view(&opts),
            "convergence" => s.convergence_view(&opts),
            "compare" => s.compare_view(&opts),
            "spread" => s.spread_view(&opts),
            other => return Err(JsError::new(&format!("unknown view '{other}'"))),
        }
        .map_err(err)?;
        Ok(bytes(&v.png))
    }

    /// x, y (arcsec), kappa and magnification under PNG pixel `(px, py)` of the kappa view, or
    /// `null` outside the map.
    pub fn hover(&self, options: JsValue, px: f32, py: f32) -> Result<JsValue, JsError> {
        let opts = view_options(options)?;
        match self.inner.hover(&opts, px, py).map_err(err)? {
            Some(h) => to_js(&h),
            None => Ok(JsValue::NULL),
        }
    }

    /// The read-out at the point `(x, y)` (arcsec) of the kappa view drawn with `options`:
    /// as [`AppSession::hover`]'s, for a typed position.
    pub fn point_readout(&self, options: JsValue, x: f64, y: f64) -> Result<JsValue, JsError> {
        let opts = view_options(options)?;
        let p = glam::DVec2::new(x, y);
        to_js(&self.inner.readout_at(&opts, p).map_err(err)?)
    }

    /// A typed or pasted position (RA/Dec in degrees or sexagesimal, or x y in arcsec) on the
    /// result's maps: `{x_arcsec, y_arcsec, form, form_words, radec_deg}`, or the error saying
    /// what could not be read ("could not read 'xyz' as a coordinate: ...").
    pub fn locate(&self, text: &str) -> Result<JsValue, JsError> {
        let t = self.inner.locate(text).map_err(err)?;
        to_js(&serde_json::json!({
            "x_arcsec": t.position_arcsec.x,
            "y_arcsec": t.position_arcsec.y,
            "form": t.form,
            "form_words": t.form.words(),
            "radec_deg": t.radec_deg,
        }))
    }

    /// The source behind the point `(x, y)` (arcsec; a hover read-out's `x_arcsec, y_arcsec`)
    /// and all its images at the curves' z_s: `{x_arcsec, y_arcsec, z_source, beta_arcsec,
    /// images: [{position_arcsec, magnification}]}`. The view option `pin_arcsec: [x, y]` draws
    /// them.
    pub fn counter_images(&self, x: f64, y: f64) -> Result<JsValue, JsError> {
        let c = self
            .inner
            .counter_images(glam::DVec2::new(x, y))
            .map_err(err)?;
        to_js(&c)
    }

    /// The same as a DS9 region file (`Session::counter_image_regions`).
    pub fn counter_image_regions(&self, x: f64, y: f64) -> Result<String, JsError> {
        let p = glam::DVec2::new(x, y);
        self.inner.counter_image_regions(p).map_err(err)
    }

    /// Per-system reports (`sources.json` as objects), each with `rgb`: the CSS colour of its
    /// arc pixels in the views (`null` for catalogue systems, drawn as markers).
    pub fn sources(&self) -> Result<JsValue, JsError> {
        let r = self.inner.result().map_err(err)?;
        let Some(x) = r.reconstruction() else {
            return Ok(js_sys::Array::new().into());
        };
        let mut rows = serde_json::to_value(&x.sources).map_err(err)?;
        for row in rows.as_array_mut().into_iter().flatten() {
            let id = row.get("id").and_then(|v| v.as_str()).unwrap_or_default();
            let rgb = r
                .marks
                .system_rgb(id)
                .map(|[red, green, blue]| format!("rgb({red}, {green}, {blue})"));
            if let Some(obj) = row.as_object_mut() {
                obj.insert("rgb".to_string(), rgb.into());
            }
        }
        to_js(&rows)
    }

    /// A download: `summary.json`, `sources.json`, `images.reg`, `convergence.json`,
    /// `critical-curves.json`, `critical-curves.reg`, `ensemble.json` or `project.json` as
    /// text.
    pub fn text_file(&self, name: &str) -> Result<String, JsError> {
        if name == "project.json" {
            return self.inner.project_json().map_err(err);
        }
        let r = self.inner.result().map_err(err)?;
        match name {
            "summary.json" => r.summary_json().map_err(err),
            "sources.json" => r.sources_json().map_err(err),
            "convergence.json" => r.convergence_json().map_err(err),
            "critical-curves.json" => Ok(r.products().curves_json()),
            "critical-curves.reg" => Ok(r.products().regions()),
            "images.reg" => r.images_regions().map_err(err),
            "ensemble.json" => self.inner.ensemble_json().map_err(err),
            other => Err(JsError::new(&format!("unknown file '{other}'"))),
        }
    }

    /// The HFF-style FITS maps: an array of `{name, bytes}`.
    pub fn fits_files(&self) -> Result<JsValue, JsError> {
        let r = self.inner.result().map_err(err)?;
        let files = r.products().fits_files().map_err(err)?;
        files_js(files.iter().map(|(n, b)| (*n, b.as_slice())))
    }

    /// Replaces the session by a project file; returns `{name, result, message}`.
    pub fn open_project(&mut self, text: &str, name: &str) -> Result<JsValue, JsError> {
        to_js(&self.inner.open_project(text, name).map_err(err)?)
    }

    /// Which files are loaded: `{images, members, arcs, model, deflection_x, deflection_y}`
    /// (names or null), and `sky_warnings`: one sentence per file whose sky positions lie
    /// apart from the others' (files of different clusters), and `missing_potfile`: the
    /// member catalogue a loaded `.par` names and that is not loaded (or null),
    /// `model_is_par`: whether the model file is a Lenstool `.par` that reads, and
    /// `model_z_lens_note`: [`crate::app::Session::model_z_lens_note`] (or null).
    pub fn loaded(&self) -> Result<JsValue, JsError> {
        let d = &self.inner.data;
        let name = |t: &Option<crate::app::NamedText>| t.as_ref().map(|x| x.name.clone());
        let fits = |k: usize| d.deflection[k].as_ref().map(|x| x.name.clone());
        to_js(&serde_json::json!({
            "images": name(&d.images), "members": name(&d.members), "arcs": name(&d.arcs),
            "model": name(&d.model), "shear": name(&d.shear),
            "deflection_x": fits(0), "deflection_y": fits(1),
            "sky_warnings": self.inner.sky_warnings(),
            "missing_potfile": d.missing_potfile(&self.inner.settings.par_options()),
            "model_is_par": d.model_is_par(&self.inner.settings.par_options()),
            "model_z_lens_note": self.inner.model_z_lens_note(),
        }))
    }
}

/// The rows of [`AppSession::strength_trial`] the page hands back, one per candidate.
fn trials_of(trials: JsValue) -> Result<Vec<crate::reconstruct::StrengthCandidate>, JsError> {
    serde_wasm_bindgen::from_value(trials).map_err(|e| JsError::new(&format!("trials: {e}")))
}
