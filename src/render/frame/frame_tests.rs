use crate::render::frame::span_union;
use std::time::{Duration, Instant};

// Compilations on several threads at once count once, and only inside
// the render: the time subtracted never exceeds the render's own.
#[test]
fn waits_count_their_union_inside_the_render() {
    let t0 = Instant::now();
    let at = |ms: u64| t0 + Duration::from_millis(ms);
    let span = |a: u64, b: u64| (at(a), at(b));
    let render = span(10, 100);
    let union = |s: &[(Instant, Instant)]| span_union(s.iter().copied(), render);
    assert_eq!(union(&[]), Duration::ZERO);
    // Two threads compiling at once, and one span half before the render.
    let overlapping = [span(20, 60), span(30, 70), span(0, 15)];
    assert_eq!(union(&overlapping), Duration::from_millis(55));
    // Disjoint spans add; one past the render's end is cut there.
    let disjoint = [span(20, 30), span(40, 50), span(95, 200)];
    assert_eq!(union(&disjoint), Duration::from_millis(25));
    // Sixteen threads each waiting the whole render: the render itself.
    let all = vec![span(0, 500); 16];
    assert_eq!(union(&all), Duration::from_millis(90));
}
