//! The one place that talks to JavaScript (compiled for wasm32 only).
//!
//! Inputs are deserialised once with `serde-wasm-bindgen`; results are plain JS objects holding
//! typed arrays (PNG bytes) and serde structs; every error becomes a `JsError` whose message
//! is the core's (it names the file, line or field).

use serde::Serialize;
use wasm_bindgen::prelude::*;

mod ensemble;
mod playground;
mod session;

use crate::demo::CLUSTER_MODEL_JSON;
use crate::model::ModelFile;
use crate::products::{ProductOptions, Products};

/// Name of the global (the worker's `self`) that holds the message of the last panic.
const PANIC_GLOBAL: &str = "wslapPanic";

/// Installs, once, a panic hook that hands a panic's message to JavaScript: WebAssembly has
/// no unwinding, so a panic aborts the instance with a bare "unreachable" and leaves it
/// unusable; the hook first sets the global `wslapPanic` to the message, which
/// `www/worker.js` reports when it replaces the instance.
pub(crate) fn keep_panic_messages() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        std::panic::set_hook(Box::new(|info| {
            let payload = info.payload();
            let message = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic without a message".to_string());
            let _ = js_sys::Reflect::set(
                &js_sys::global(),
                &JsValue::from_str(PANIC_GLOBAL),
                &JsValue::from_str(&message),
            );
        }));
    });
}

/// The crate version, shown by the app.
#[wasm_bindgen]
pub fn version() -> String {
    env!("CARGO_PKG_VERSION").to_string()
}

/// The built-in example model file (JSON text).
#[wasm_bindgen]
pub fn example_model_json() -> String {
    CLUSTER_MODEL_JSON.to_string()
}

/// Parses and validates a model file; the error names `source_name`, the line or the component.
#[wasm_bindgen]
pub fn validate_model(text: &str, source_name: &str) -> Result<(), JsError> {
    ModelFile::from_json_str(text, source_name)?;
    Ok(())
}

/// Maps, critical curves and the kappa figure of a model file.
///
/// `options` is a `ProductOptions` object (`z_source`, `size_arcsec`, `pixels`, `scale`);
/// missing fields take their defaults. Returns `{ png: Uint8Array, summary, curves }`.
#[wasm_bindgen]
pub fn forward_products(model_text: &str, options: JsValue) -> Result<JsValue, JsError> {
    let opts: ProductOptions = if options.is_undefined() || options.is_null() {
        ProductOptions::default()
    } else {
        serde_wasm_bindgen::from_value(options)
            .map_err(|e| JsError::new(&format!("options: {e}")))?
    };
    let model = ModelFile::from_json_str(model_text, "model")?;
    let products = Products::from_model(&model, &opts)?;
    let png = products.kappa_png(opts.scale)?;
    let out = js_sys::Object::new();
    set(
        &out,
        "png",
        &js_sys::Uint8Array::from(png.as_slice()).into(),
    )?;
    set(&out, "summary", &to_js(&products.summary())?)?;
    set(&out, "curves", &to_js(&products.curves)?)?;
    Ok(out.into())
}

fn to_js<T: Serialize>(value: &T) -> Result<JsValue, JsError> {
    value
        .serialize(&serde_wasm_bindgen::Serializer::json_compatible())
        .map_err(|e| JsError::new(&e.to_string()))
}

fn set(obj: &js_sys::Object, key: &str, value: &JsValue) -> Result<(), JsError> {
    js_sys::Reflect::set(obj, &JsValue::from_str(key), value)
        .map(|_| ())
        .map_err(|_| JsError::new("could not build the result object"))
}
