//! The ensemble's pieces on [`AppSession`] (see `crate::app`'s ensemble module): the main
//! worker makes the plan, pool workers run its members (`www/js/ensemble.js`), and the main
//! worker combines what they hand back. Thin conversions; the work is the core's.

use wasm_bindgen::prelude::*;

use crate::app::member_run;
use crate::reconstruct::{EnsembleMember, EnsemblePlan};

use super::session::{err, files_js, reporter, AppSession};
use super::{set, to_js};

/// A member as a pool worker handed it over, kept until the ensemble is combined.
pub(crate) struct HandedMember {
    record: EnsembleMember,
    kappa: Vec<f64>,
    magnif: Vec<f64>,
}

fn plan_from(plan: JsValue) -> Result<EnsemblePlan, JsError> {
    serde_wasm_bindgen::from_value(plan).map_err(|e| JsError::new(&format!("ensemble plan: {e}")))
}

#[wasm_bindgen]
impl AppSession {
    /// The plan of the ensemble the settings ask for after the last reconstruction (every
    /// member's systems and grid shift, drawn from `ensemble.seed` as `wslap reconstruct
    /// --ensemble` draws them), or `null` when `ensemble.members` is 0. Forgets the members
    /// handed over for an earlier plan.
    pub fn ensemble_plan(&mut self) -> Result<JsValue, JsError> {
        self.ensemble_runs.clear();
        match self.inner.ensemble_plan().map_err(err)? {
            Some(plan) => to_js(&plan),
            None => Ok(JsValue::NULL),
        }
    }

    /// Member `member` (1-based) of `plan` on this session's data and settings:
    /// `{record, kappa: Float64Array, magnif: Float64Array}` (its `ensemble.json` entry, its
    /// kappa and its magnification on the plan's map, row by row). `progress` gets the
    /// reports as [`AppSession::run`]'s, with `member`. The session's result is not touched.
    pub fn ensemble_member(
        &self,
        plan: JsValue,
        member: usize,
        progress: &js_sys::Function,
    ) -> Result<JsValue, JsError> {
        let plan = plan_from(plan)?;
        let mut report = reporter(progress, [("member", member as f64)]);
        let run = self
            .inner
            .ensemble_member(&plan, member, &mut report)
            .map_err(err)?;
        let out = js_sys::Object::new();
        set(&out, "record", &to_js(&run.record)?)?;
        let array = |data: &[f64]| JsValue::from(js_sys::Float64Array::from(data));
        set(&out, "kappa", &array(&run.kappa.data))?;
        set(&out, "magnif", &array(&run.magnif.data))?;
        Ok(out.into())
    }

    /// Keeps a member of the current plan as [`AppSession::ensemble_member`] gave it, until
    /// [`AppSession::ensemble_finish`].
    pub fn ensemble_add(
        &mut self,
        record: JsValue,
        kappa: Vec<f64>,
        magnif: Vec<f64>,
    ) -> Result<(), JsError> {
        let record: EnsembleMember = serde_wasm_bindgen::from_value(record)
            .map_err(|e| JsError::new(&format!("ensemble member: {e}")))?;
        self.ensemble_runs.push(HandedMember {
            record,
            kappa,
            magnif,
        });
        Ok(())
    }

    /// Combines the members handed over into the result's ensemble (`complete`: all of
    /// `plan`'s); returns [`AppSession::result_info`], whose summary now has the intervals.
    pub fn ensemble_finish(&mut self, plan: JsValue, complete: bool) -> Result<JsValue, JsError> {
        let plan = plan_from(plan)?;
        let runs = std::mem::take(&mut self.ensemble_runs)
            .into_iter()
            .map(|m| member_run(&plan, m.record, m.kappa, m.magnif))
            .collect::<Result<Vec<_>, _>>()
            .map_err(err)?;
        self.inner
            .set_ensemble(&plan, runs, complete)
            .map_err(err)?;
        self.result_info()
    }

    /// The result's ensemble (`ensemble.json` as an object, with `maps`: whether its
    /// statistics maps are at hand, for the spread view, the read-out and the FITS), or `null`.
    pub fn ensemble_info(&self) -> Result<JsValue, JsError> {
        match self.inner.ensemble() {
            Some(e) => {
                let mut info = serde_json::to_value(e).map_err(|e| JsError::new(&e.to_string()))?;
                info["maps"] = serde_json::Value::Bool(e.maps.is_some());
                to_js(&info)
            }
            None => Ok(JsValue::NULL),
        }
    }

    /// The ensemble's maps and figure as files: an array of `{name, bytes}`
    /// (`kappa-mean.fits`, `kappa-std.fits`, `magnif-p16.fits`, `magnif-p50.fits`,
    /// `magnif-p84.fits`, `kappa-std.png`).
    pub fn ensemble_files(&self) -> Result<JsValue, JsError> {
        let files = self.inner.ensemble_files().map_err(err)?;
        files_js(files.iter().map(|(n, b)| (n.as_str(), b.as_slice())))
    }
}
