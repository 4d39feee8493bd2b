//! `PlaygroundSession`: the live lensing playground ([`crate::playground`]) as a JavaScript
//! class living in `www/playground/worker.js`. Every method is a thin conversion.

use glam::DVec2;
use wasm_bindgen::prelude::*;

use crate::playground::{observe, ContourKind, ObserveOptions, Playground, Scene, SourcePixels};

use super::{set, to_js};

fn err(e: impl std::fmt::Display) -> JsError {
    JsError::new(&e.to_string())
}

/// One playground: a scene and the pictures uploaded for it.
#[wasm_bindgen]
pub struct PlaygroundSession {
    inner: Playground,
}

#[wasm_bindgen]
impl PlaygroundSession {
    /// A playground showing the scene `scene_json` (format in the crate's `playground` docs).
    #[wasm_bindgen(constructor)]
    pub fn new(scene_json: &str) -> Result<PlaygroundSession, JsError> {
        super::keep_panic_messages();
        let scene = Scene::from_json_str(scene_json).map_err(err)?;
        Ok(Self {
            inner: Playground::new(scene).map_err(err)?,
        })
    }

    /// Replaces the scene; on error the old one stays and the message names the field.
    pub fn set_scene(&mut self, scene_json: &str) -> Result<(), JsError> {
        let scene = Scene::from_json_str(scene_json).map_err(err)?;
        self.inner.set_scene(scene).map_err(err)
    }

    /// The scene as compact JSON.
    pub fn scene_json(&self) -> String {
        self.inner.scene().to_json_string()
    }

    /// The scene's lens as a model file (JSON), member galaxies expanded into their halos.
    pub fn truth_model_json(&self) -> Result<String, JsError> {
        Ok(self
            .inner
            .scene()
            .truth_model()
            .map_err(err)?
            .to_json_string())
    }

    /// The scene observed as mock data (`options_json`: the `ObserveOptions` fields, any
    /// missing ones at their defaults; `""` for all defaults): `{images_cat?, arcs_json?,
    /// members_cat?, model_json, z_lens, settings: [[path, value]], systems, notes}`.
    pub fn observe(&self, options_json: &str) -> Result<JsValue, JsError> {
        let options: ObserveOptions = if options_json.trim().is_empty() {
            ObserveOptions::default()
        } else {
            serde_json::from_str(options_json).map_err(|e| err(format!("observe options: {e}")))?
        };
        to_js(&observe(self.inner.scene(), &options).map_err(err)?)
    }

    /// Holds `width x height` RGBA pixels for the image sources with `slot`.
    pub fn set_picture(
        &mut self,
        slot: u32,
        width: usize,
        height: usize,
        rgba: Vec<u8>,
    ) -> Result<(), JsError> {
        if width == 0 || height == 0 || rgba.len() != width * height * 4 {
            return Err(JsError::new(&format!(
                "picture: {} bytes is not {width} x {height} RGBA pixels",
                rgba.len()
            )));
        }
        self.inner.set_picture(
            slot,
            SourcePixels {
                width,
                height,
                rgba,
            },
        );
        Ok(())
    }

    /// Both views at `pixels` a side: `{pixels, image: Uint8ClampedArray, source:
    /// Uint8ClampedArray, curves, points, compute_ms}`.
    pub fn frame(&self, pixels: usize) -> Result<JsValue, JsError> {
        let frame = self.inner.frame(pixels);
        let out = to_js(&frame)?;
        let obj = out
            .dyn_ref::<js_sys::Object>()
            .ok_or_else(|| JsError::new("frame is not an object"))?;
        let image = js_sys::Uint8ClampedArray::from(frame.image_rgba.as_slice());
        let source = js_sys::Uint8ClampedArray::from(frame.source_rgba.as_slice());
        set(obj, "image", &image.into())?;
        set(obj, "source", &source.into())?;
        Ok(out)
    }

    /// Where the ray seen at `(x, y)` arcsec lands on each source plane.
    pub fn ray(&self, x: f64, y: f64) -> Result<JsValue, JsError> {
        to_js(&self.inner.ray(DVec2::new(x, y)))
    }

    /// Every image of a point source at `(x, y)` arcsec and redshift `z`.
    pub fn images_of(&self, x: f64, y: f64, z: f64) -> Result<JsValue, JsError> {
        to_js(&self.inner.images_of(DVec2::new(x, y), z))
    }

    /// Contours `kind` ("kappa", "magnification", "arrival") at `pixels` a side for a source
    /// at redshift `z` and position `(x, y)` arcsec.
    pub fn contours(
        &self,
        kind: &str,
        pixels: usize,
        z: f64,
        x: f64,
        y: f64,
    ) -> Result<JsValue, JsError> {
        let kind = match kind {
            "kappa" => ContourKind::Kappa,
            "magnification" => ContourKind::Magnification,
            "arrival" => ContourKind::ArrivalTime,
            other => {
                return Err(JsError::new(&format!(
                    "contours: kind \"{other}\" is not kappa, magnification or arrival"
                )))
            }
        };
        to_js(&self.inner.contours(kind, pixels, z, DVec2::new(x, y)))
    }
}
