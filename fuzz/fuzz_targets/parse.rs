//! Arbitrary bytes, read as UTF-8 (lossily), as an ibeam scene and as a
//! Fidget `.vm` model: loading returns a scene or a diagnostic, never
//! panics. The loader turns a panic on its own thread into an "internal
//! error" diagnostic, so that message is a failure too.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    for name in ["fuzz.ib", "fuzz.vm"] {
        if let Err(e) = ibeam::lang::load_scene_source(name, &text) {
            assert!(
                !e.message.contains("internal error"),
                "{name}: loader panicked on {text:?}: {e}"
            );
        }
    }
    if let Err(e) = ibeam::lang::function_from_formula(&text) {
        assert!(
            !e.message.contains("internal error"),
            "formula: loader panicked on {text:?}: {e}"
        );
    }
});
