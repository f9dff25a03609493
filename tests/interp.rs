//! The evaluator conformance suite (tests/common) run on the interpreter.

mod common;

use ibeam::eval::Evaluator;
use ibeam::eval::interp::Interpreter;
use ibeam::ir::Function;

fn make(f: &Function) -> Box<dyn Evaluator> {
    Box::new(Interpreter::new(f.clone()))
}

#[test]
fn point_ops() {
    common::check_point_ops(&make);
}

#[test]
fn interval_ops() {
    common::check_interval_ops(&make);
}

#[test]
fn grad_ops() {
    common::check_grad_ops(&make);
}

#[test]
fn random_functions() {
    common::check_random_functions(&make, 0..300);
}
