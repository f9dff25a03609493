//! `ibeam eval`: evaluate each object at a point or over a box.

use super::{CliError, EvalKind, build_evaluators, emit, parse_numbers};
use ibeam::eval::affine::AffineEvaluator;
use ibeam::interval::Interval;
use std::fmt::Write;

/// Arguments of `ibeam eval`.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("where").required(true).args(["at", "box"])))]
pub struct Args {
    /// Scene file (`.ib`) or Fidget model (`.vm`).
    pub file: std::path::PathBuf,
    /// Point `X,Y,Z`: prints f and its gradient.
    #[arg(long, allow_hyphen_values = true, value_name = "X,Y,Z")]
    pub at: Option<String>,
    /// Box `X0,X1,Y0,Y1,Z0,Z1`: prints an interval containing f over it.
    #[arg(
        long = "box",
        id = "box",
        allow_hyphen_values = true,
        value_name = "X0,X1,Y0,Y1,Z0,Z1"
    )]
    pub bbox: Option<String>,
    /// Evaluator: the JIT, or the reference interpreter.
    #[arg(long = "eval", value_enum, default_value_t = EvalKind::Jit)]
    pub eval: EvalKind,
    /// How `--box` encloses f: interval arithmetic, or reduced affine
    /// forms intersected with it (never wider; costs a few times an
    /// interval evaluation; the interpreter's, or for `--eval jit` the
    /// tape's, as native code has no affine kind).
    #[arg(long, value_enum, default_value_t = Enclosure::Interval)]
    pub enclosure: Enclosure,
}

/// The enclosures `ibeam eval --box` prints.
#[derive(Copy, Clone, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Enclosure {
    /// Outward-rounded interval arithmetic.
    Interval,
    /// Reduced affine arithmetic (see `ibeam::ir::affine_rules`).
    Affine,
}

/// Runs `ibeam eval`. Numbers print with `{:e}`, the shortest text that
/// reads back as the same f64.
pub fn run(args: &Args) -> Result<(), CliError> {
    let scene = ibeam::lang::load_scene(&args.file)?;
    let evaluators = build_evaluators(&scene, args.eval)?;
    let mut out = String::new();
    for (object, eval) in scene.objects.iter().zip(&evaluators) {
        if let Some(at) = &args.at {
            let p = parse_numbers(at, 3, "--at")?;
            let g = eval.point_grad([p[0], p[1], p[2]]);
            let _ = writeln!(
                out,
                "{}: f = {:e}  grad = ({:e}, {:e}, {:e})",
                object.name, g.v, g.d[0], g.d[1], g.d[2]
            );
        }
        if let Some(b) = &args.bbox {
            let v = parse_numbers(b, 6, "--box")?;
            for axis in 0..3 {
                if v[2 * axis] > v[2 * axis + 1] {
                    return Err(format!(
                        "--box: the {} range {}..{} is reversed",
                        ["x", "y", "z"][axis],
                        v[2 * axis],
                        v[2 * axis + 1]
                    )
                    .into());
                }
            }
            let bx = [
                Interval::new(v[0], v[1]),
                Interval::new(v[2], v[3]),
                Interval::new(v[4], v[5]),
            ];
            let r = match args.enclosure {
                Enclosure::Interval => eval.interval(bx),
                Enclosure::Affine => affine(object, args.eval, bx),
            };
            if r.is_empty() {
                let _ = writeln!(
                    out,
                    "{}: empty (f is undefined on the whole box)",
                    object.name
                );
            } else {
                let _ = writeln!(out, "{}: [{:e}, {:e}]", object.name, r.lo, r.hi);
            }
        }
    }
    emit(&out)
}

/// The affine enclosure of `object`'s simplified function over `b`, by
/// the interpreter or a tape (see [`Args::enclosure`]).
fn affine(object: &ibeam::scene::Object, kind: EvalKind, b: [Interval; 3]) -> Interval {
    let f = ibeam::ir::passes::simplify(&object.function);
    match kind {
        EvalKind::Interp => ibeam::eval::interp::Interpreter::new(f).affine(b),
        EvalKind::Jit => ibeam::eval::tape::Tape::new(&f).affine(b),
    }
}
