//! Turns the parsed items of a scene file into a validated [`Scene`]:
//! lowers the objects and checks camera, lights, bounds and render
//! settings, filling in defaults.

use super::ast::{Expr, Ident, Item, Prop, PropValue, Span};
use super::diag::Diag;
use crate::ir::Function;
use crate::lang::diag::suggest;
use crate::lang::lower::{Program, depends_on_coords};
use crate::scene::{Bounds, Camera, Light, LightKind, Object, Projection, RenderSettings, Scene};

/// The colour of an object without a `color` property.
pub const DEFAULT_OBJECT_COLOR: [f64; 3] = [0.8, 0.8, 0.8];

/// The largest image side accepted in `render { size = … }`.
pub const MAX_IMAGE_SIDE: u32 = 16384;

fn span_diag(src: usize, span: Span, message: String) -> Diag {
    Diag::new(src, span.0..span.1, message)
}

/// Checks a block's properties against the allowed names and rejects
/// duplicates; returns them in order.
fn check_props<'a>(
    src: usize,
    block: &str,
    props: &'a [Prop],
    allowed: &[&str],
) -> Result<Vec<&'a Prop>, Diag> {
    let mut seen: Vec<&Prop> = Vec::new();
    for p in props {
        if !allowed.contains(&p.name.name.as_str()) {
            let d = span_diag(
                src,
                p.name.span,
                format!("unknown property `{}` in {block}", p.name.name),
            );
            return Err(match suggest(&p.name.name, allowed.iter().copied()) {
                Some(s) => d.with_help(format!("did you mean `{s}`?")),
                None => d.with_help(format!("allowed here: {}", allowed.join(", "))),
            });
        }
        if let Some(q) = seen.iter().find(|q| q.name.name == p.name.name) {
            return Err(span_diag(
                src,
                p.name.span,
                format!("`{}` is set twice in {block}", p.name.name),
            )
            .with_secondary(src, q.name.span.0..q.name.span.1, "first set here"));
        }
        seen.push(p);
    }
    Ok(seen)
}

fn find<'a>(props: &[&'a Prop], name: &str) -> Option<&'a Prop> {
    props.iter().copied().find(|p| p.name.name == name)
}

fn scalar(prog: &Program, src: usize, p: &Prop) -> Result<f64, Diag> {
    match &p.value {
        PropValue::Expr(e) => {
            let v = prog.constant(e, src, &format!("`{}`", p.name.name))?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(span_diag(
                    src,
                    e.span,
                    format!("`{}` must be finite, but it is {v}", p.name.name),
                ))
            }
        }
        other => Err(span_diag(
            src,
            other.span(),
            format!("`{}` must be a number", p.name.name),
        )),
    }
}

fn tuple(
    prog: &Program,
    src: usize,
    what: &str,
    elems: &[Expr],
    span: Span,
    n: usize,
) -> Result<Vec<f64>, Diag> {
    if elems.len() != n {
        return Err(span_diag(
            src,
            span,
            format!(
                "{what} must have {n} components, but it has {}",
                elems.len()
            ),
        ));
    }
    elems
        .iter()
        .map(|e| {
            let v = prog.constant(e, src, what)?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(span_diag(
                    src,
                    e.span,
                    format!("{what} must be finite, but this is {v}"),
                ))
            }
        })
        .collect()
}

fn vec3(prog: &Program, src: usize, p: &Prop) -> Result<[f64; 3], Diag> {
    let what = format!("`{}`", p.name.name);
    match &p.value {
        PropValue::Tuple(elems, span) => {
            let v = tuple(prog, src, &what, elems, *span, 3)?;
            Ok([v[0], v[1], v[2]])
        }
        other => Err(span_diag(
            src,
            other.span(),
            format!("{what} must be a triple `(a, b, c)`"),
        )),
    }
}

fn color(prog: &Program, src: usize, p: &Prop) -> Result<[f64; 3], Diag> {
    let c = vec3(prog, src, p)?;
    if c.iter().any(|v| *v < 0.0) {
        return Err(span_diag(
            src,
            p.value.span(),
            format!("`{}` components must not be negative", p.name.name),
        ));
    }
    Ok(c)
}

fn boolean(src: usize, p: &Prop) -> Result<bool, Diag> {
    match &p.value {
        PropValue::Bool(b, _) => Ok(*b),
        other => Err(span_diag(
            src,
            other.span(),
            format!("`{}` must be `true` or `false`", p.name.name),
        )),
    }
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn camera(prog: &Program, src: usize, kw: &Ident, props: &[Prop]) -> Result<Camera, Diag> {
    let ps = check_props(
        src,
        "camera",
        props,
        &["eye", "target", "up", "fov", "ortho"],
    )?;
    let mut cam = Camera::default();
    if let Some(p) = find(&ps, "eye") {
        cam.eye = vec3(prog, src, p)?;
    }
    if let Some(p) = find(&ps, "target") {
        cam.target = vec3(prog, src, p)?;
    }
    if let Some(p) = find(&ps, "up") {
        cam.up = vec3(prog, src, p)?;
    }
    match (find(&ps, "fov"), find(&ps, "ortho")) {
        (Some(_), Some(o)) => {
            return Err(span_diag(
                src,
                o.name.span,
                "a camera has either `fov` or `ortho`, not both".into(),
            ));
        }
        (Some(p), None) => {
            let fov = scalar(prog, src, p)?;
            if !(fov > 0.0 && fov < 180.0) {
                return Err(span_diag(
                    src,
                    p.value.span(),
                    format!("`fov` must be between 0 and 180 degrees, but it is {fov}"),
                ));
            }
            cam.projection = Projection::Perspective { fov_deg: fov };
        }
        (None, Some(p)) => {
            let width = scalar(prog, src, p)?;
            if width <= 0.0 {
                return Err(span_diag(
                    src,
                    p.value.span(),
                    format!("`ortho` (the view width) must be positive, but it is {width}"),
                ));
            }
            cam.projection = Projection::Orthographic { width };
        }
        (None, None) => {}
    }
    let dir = [
        cam.target[0] - cam.eye[0],
        cam.target[1] - cam.eye[1],
        cam.target[2] - cam.eye[2],
    ];
    let at = |name: &str| find(&ps, name).map_or(kw.span, |p| p.value.span());
    if norm(dir) == 0.0 {
        return Err(span_diag(
            src,
            at("target"),
            "the camera's `eye` and `target` are the same point".into(),
        ));
    }
    let u = cam.up;
    let cross = [
        u[1] * dir[2] - u[2] * dir[1],
        u[2] * dir[0] - u[0] * dir[2],
        u[0] * dir[1] - u[1] * dir[0],
    ];
    if norm(cross) <= 1e-9 * norm(u) * norm(dir) {
        return Err(span_diag(
            src,
            at("up"),
            "the camera's `up` is zero or parallel to the view direction".into(),
        )
        .with_help("`up` only needs to point roughly upward, e.g. `(0, 1, 0)` or `(0, 0, 1)`"));
    }
    Ok(cam)
}

fn light(prog: &Program, src: usize, kw: &Ident, props: &[Prop]) -> Result<Light, Diag> {
    let ps = check_props(
        src,
        "light",
        props,
        &["position", "direction", "color", "shadows"],
    )?;
    let kind = match (find(&ps, "position"), find(&ps, "direction")) {
        (Some(_), Some(d)) => {
            return Err(span_diag(
                src,
                d.name.span,
                "a light has either `position` or `direction`, not both".into(),
            ));
        }
        (Some(p), None) => LightKind::Point(vec3(prog, src, p)?),
        (None, Some(p)) => {
            let d = vec3(prog, src, p)?;
            if norm(d) == 0.0 {
                return Err(span_diag(
                    src,
                    p.value.span(),
                    "a light's `direction` must not be zero".into(),
                ));
            }
            LightKind::Directional(d)
        }
        (None, None) => {
            return Err(span_diag(
                src,
                kw.span,
                "a light needs a `position` or a `direction`".into(),
            )
            .with_help("e.g. `light { direction = (-1, -1, -1); }`"));
        }
    };
    let color = match find(&ps, "color") {
        Some(p) => color(prog, src, p)?,
        None => [1.0, 1.0, 1.0],
    };
    let shadows = match find(&ps, "shadows") {
        Some(p) => boolean(src, p)?,
        None => false,
    };
    Ok(Light {
        kind,
        color,
        shadows,
    })
}

fn render(prog: &Program, src: usize, props: &[Prop]) -> Result<RenderSettings, Diag> {
    let ps = check_props(src, "render", props, &["size", "background"])?;
    let mut r = RenderSettings::default();
    if let Some(p) = find(&ps, "size") {
        let PropValue::Tuple(elems, span) = &p.value else {
            return Err(span_diag(
                src,
                p.value.span(),
                "`size` must be a pair `(width, height)`".into(),
            ));
        };
        let v = tuple(prog, src, "`size`", elems, *span, 2)?;
        let mut side = [0u32; 2];
        for (i, (s, e)) in v.iter().zip(elems).enumerate() {
            if s.fract() != 0.0 || *s < 1.0 || *s > f64::from(MAX_IMAGE_SIDE) {
                return Err(span_diag(
                    src,
                    e.span,
                    format!(
                        "image sizes must be whole numbers from 1 to {MAX_IMAGE_SIDE}, but this is {s}"
                    ),
                ));
            }
            side[i] = *s as u32;
        }
        r.size = (side[0], side[1]);
    }
    if let Some(p) = find(&ps, "background") {
        r.background = color(prog, src, p)?;
    }
    Ok(r)
}

fn bounds(
    prog: &Program,
    src: usize,
    min: &(Vec<Expr>, Span),
    max: &(Vec<Expr>, Span),
) -> Result<Bounds, Diag> {
    let lo = tuple(prog, src, "a bounds corner", &min.0, min.1, 3)?;
    let hi = tuple(prog, src, "a bounds corner", &max.0, max.1, 3)?;
    for i in 0..3 {
        if lo[i] >= hi[i] {
            let axis = ["x", "y", "z"][i];
            return Err(span_diag(
                src,
                (min.1.0, max.1.1),
                format!(
                    "empty bounds: the minimum {axis} ({}) is not below the maximum ({})",
                    lo[i], hi[i]
                ),
            )
            .with_help("write `bounds = (min x, min y, min z) .. (max x, max y, max z);`"));
        }
    }
    Ok(Bounds {
        min: [lo[0], lo[1], lo[2]],
        max: [hi[0], hi[1], hi[2]],
    })
}

/// Lowers an object named `name` unless an object of `earlier` has its name.
fn object(
    prog: &Program,
    src: usize,
    name: &Ident,
    body: &Expr,
    props: &[Prop],
    earlier: &[&Ident],
) -> Result<Object, Diag> {
    if let Some(prev) = earlier.iter().find(|n| n.name == name.name) {
        return Err(span_diag(
            src,
            name.span,
            format!("object `{}` is defined twice", name.name),
        )
        .with_secondary(src, prev.span.0..prev.span.1, "first defined here"));
    }
    let function = prog.lower(body, src)?;
    if !depends_on_coords(&function) {
        return Err(span_diag(
            src,
            body.span,
            "this is not a shape: it does not depend on x, y or z".into(),
        ));
    }
    let ps = check_props(src, "an object", props, &["color"])?;
    let color = match find(&ps, "color") {
        Some(p) => color(prog, src, p)?,
        None => DEFAULT_OBJECT_COLOR,
    };
    Ok(Object {
        name: name.name.clone(),
        function,
        color,
    })
}

/// Lowers and validates the items of source `src` (whose text is
/// `text_len` bytes long) into a scene.
pub fn build(prog: &Program, items: &[Item], src: usize, text_len: usize) -> Result<Scene, Diag> {
    let mut objects: Vec<Object> = Vec::new();
    let mut object_names: Vec<&Ident> = Vec::new();
    let mut cam: Option<(Camera, &Ident)> = None;
    let mut rend: Option<(RenderSettings, &Ident)> = None;
    let mut bnd: Option<(Bounds, Span)> = None;
    let mut lights = Vec::new();
    for item in items {
        match item {
            Item::Let { .. } | Item::Fn { .. } | Item::Import { .. } => {}
            Item::Object { name, body, props } => {
                objects.push(object(prog, src, name, body, props, &object_names)?);
                object_names.push(name);
            }
            Item::Block { keyword, props } => match keyword.name.as_str() {
                "camera" => {
                    if let Some((_, prev)) = cam {
                        return Err(duplicate_block(src, keyword, prev));
                    }
                    cam = Some((camera(prog, src, keyword, props)?, keyword));
                }
                "render" => {
                    if let Some((_, prev)) = rend {
                        return Err(duplicate_block(src, keyword, prev));
                    }
                    rend = Some((render(prog, src, props)?, keyword));
                }
                _ => lights.push(light(prog, src, keyword, props)?),
            },
            Item::Bounds { span, min, max } => {
                if let Some((_, prev)) = bnd {
                    return Err(span_diag(src, *span, "`bounds` is set twice".into())
                        .with_secondary(src, prev.0..prev.1, "first set here"));
                }
                bnd = Some((bounds(prog, src, min, max)?, *span));
            }
        }
    }
    if objects.is_empty() {
        return Err(
            span_diag(src, (text_len, text_len), "the scene has no object".into())
                .with_help("add one, e.g. `object ball = sphere(1);`"),
        );
    }
    if lights.is_empty() {
        lights.push(Light::default_light());
    }
    Ok(Scene {
        objects,
        camera: cam.map_or_else(Camera::default, |c| c.0),
        lights,
        bounds: bnd.map_or_else(Bounds::default, |b| b.0),
        render: rend.map_or_else(RenderSettings::default, |r| r.0),
    })
}

fn duplicate_block(src: usize, kw: &Ident, prev: &Ident) -> Diag {
    span_diag(src, kw.span, format!("a second `{}` block", kw.name))
        .with_secondary(src, prev.span.0..prev.span.1, "the first one is here")
        .with_help("a scene has at most one camera and one render block")
}

/// The scene of an imported `.vm` model: one object, and a view that
/// frames the [-1, 1] cube (looking down -z at the unit square when the
/// model does not use z).
pub fn vm_scene(name: String, function: Function, src: usize) -> Result<Scene, Diag> {
    if !depends_on_coords(&function) {
        return Err(Diag::new(
            src,
            0..0,
            "this is not a shape: the result does not depend on x, y or z".into(),
        ));
    }
    let flat = !function.uses_vars()[2];
    let camera = if flat {
        Camera {
            eye: [0.0, 0.0, 2.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            projection: Projection::Orthographic { width: 2.0 },
        }
    } else {
        Camera {
            eye: [2.4, 2.0, 3.2],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            projection: Projection::Perspective { fov_deg: 40.0 },
        }
    };
    Ok(Scene {
        objects: vec![Object {
            name,
            function,
            color: DEFAULT_OBJECT_COLOR,
        }],
        camera,
        lights: vec![Light::default_light()],
        bounds: Bounds {
            min: [-1.0; 3],
            max: [1.0; 3],
        },
        render: RenderSettings::default(),
    })
}
