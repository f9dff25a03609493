//! Functions with jumps and the new shape operators, end to end: the
//! examples that use them render with beam and pixel drawing the same
//! pixels, the JIT and the interpreter the same hit mask (colours within
//! 2/255), and nothing a dense
//! point march finds is missed; a staircase `y - floor(…)` draws its
//! risers as walls (the boundary of {f < 0}).

use super::*;

#[test]
fn examples_with_jumps_and_new_operators() {
    for name in ["terraces.ib", "shapes.ib"] {
        let scene = load_example(name);
        let (w, h) = (40, 30);
        let got = beam(&scene, w, h);
        assert!(
            count(&got.hit_mask) > 200,
            "{name}: {}",
            count(&got.hit_mask)
        );
        assert_beam_equals_pixel(name, &scene, &got, w, h);
        assert_covers_march(name, &scene, &got, w, h);
        let interp = render_by(&scene, &interp_evaluators(&scene), w, h, Method::Beam);
        assert_eq!(got.hit_mask, interp.hit_mask, "{name}: jit vs interp mask");
        // Colours within 2/255: the renderer prunes interpreted functions
        // from 64 ops and native ones from 512, keeping signs only
        // (`Keep::Signs`), so a root may be refined on another function
        // with the same zero set and land a rounding step away.
        let worst = got
            .image
            .as_raw()
            .iter()
            .zip(interp.image.as_raw())
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap_or(0);
        assert!(
            worst <= 2,
            "{name}: jit vs interp colours differ by {worst}"
        );
    }
}

#[test]
fn a_staircase_draws_its_risers() {
    // Seen from the side, each step's riser is a vertical wall: rays
    // straight along -z hit the solid {y < floor(4x)/4} on every row below
    // the stair's top, whatever the fraction of the step.
    let src = scene_text(
        "y - floor(4 * x) / 4",
        [0.0, 0.0, 4.0],
        [0.0, 0.0, 0.0],
        1.0,
    );
    let scene = load("stairs.ib", &src);
    let (w, h) = (32, 32);
    let got = beam(&scene, w, h);
    assert_beam_equals_pixel("stairs", &scene, &got, w, h);
    assert_covers_march("stairs", &scene, &got, w, h);
    assert!(count(&got.hit_mask) > 100);
}
