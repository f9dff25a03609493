use super::*;

// The pieces as a list front to back (the stack pops the last first).
fn front_to_back(stack: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    stack.into_iter().rev().collect()
}

#[test]
fn pieces_near_a_candidate_take_it_first_then_double() {
    let tr = Scope::for_tests(&crate::scene::Camera::default(), 64);
    let p = front_to_back(tr.first_pieces_near(1.0, 1.5, 10.0));
    assert_eq!(p[0], (1.0, 1.5));
    // Contiguous from t0 to t1, each piece at most twice as deep as
    // the one before.
    assert_eq!(p.last().unwrap().1, 10.0);
    for w in p.windows(2) {
        assert_eq!(w[0].1, w[1].0);
        assert!(w[1].1 - w[1].0 <= 2.0 * (w[0].1 - w[0].0) + 1e-12, "{p:?}");
    }
    assert_eq!(&p[1..4], &[(1.5, 2.5), (2.5, 4.5), (4.5, 8.5)]);
    // No candidate inside the range: the plain first pieces.
    assert_eq!(
        tr.first_pieces_near(1.0, 1.0, 10.0),
        tr.first_pieces(1.0, 10.0)
    );
    assert_eq!(
        tr.first_pieces_near(1.0, 12.0, 10.0),
        tr.first_pieces(1.0, 10.0)
    );
}

// The merge of the doubling ends with the slices' ends gives what
// sorting both lists together would, equal ends once.
#[test]
fn pieces_near_a_candidate_merge_like_a_sort() {
    let mut tr = Scope::for_tests(&crate::scene::Camera::default(), 64);
    let mut rng = crate::ir::random::Rng::new(7);
    for case in 0..2000 {
        let t0 = rng.unit() * 4.0;
        let near = t0 + rng.unit() * 2.0;
        let t1 = t0 + rng.unit() * 20.0;
        // Some slice ends fall exactly on doubling ends.
        let mut ends: Vec<f64> = (0..(case % 6)).map(|_| t0 + rng.unit() * 20.0).collect();
        if case % 3 == 0 {
            ends.push(near + 2.0 * (near - t0));
        }
        ends.sort_by(f64::total_cmp);
        tr.pruner.slice_ends = ends.clone().into();
        let got = tr.first_pieces_near(t0, near, t1);
        if !(t0 < near && near < t1) {
            assert_eq!(got, tr.first_pieces(t0, t1));
            continue;
        }
        let mut cuts = vec![t0];
        let (mut w, mut e) = (near - t0, near);
        while e < t1 {
            cuts.push(e);
            w *= 2.0;
            e += w;
        }
        cuts.extend(ends.iter().copied().filter(|&c| c > t0 && c < t1));
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        cuts.push(t1);
        let want: Vec<(f64, f64)> = cuts.windows(2).rev().map(|w| (w[0], w[1])).collect();
        assert_eq!(got, want, "t0 {t0} near {near} t1 {t1} ends {ends:?}");
    }
}

// A ray's candidate piece comes first; behind it, a sub-sample's
// pieces double and other rays' follow the tile's slices.
#[test]
fn a_rays_candidate_piece_comes_first() {
    let mut tr = Scope::for_tests(&crate::scene::Camera::default(), 64);
    tr.pruner.slice_ends = Arc::new([2.0, 3.0]);
    let p = front_to_back(tr.ray_pieces(1.0, 1.5, 5.0));
    assert_eq!(p, vec![(1.0, 1.5), (1.5, 2.0), (2.0, 3.0), (3.0, 5.0)]);
    // Without a candidate: the plain first pieces.
    assert_eq!(tr.ray_pieces(1.0, 1.0, 5.0), tr.first_pieces(1.0, 5.0));
    tr.ctx.sub_samples = true;
    assert_eq!(
        tr.ray_pieces(1.0, 1.5, 5.0),
        tr.first_pieces_near(1.0, 1.5, 5.0)
    );
}

#[test]
fn pieces_near_a_candidate_are_cut_at_slice_ends() {
    let mut tr = Scope::for_tests(&crate::scene::Camera::default(), 64);
    tr.pruner.slice_ends = Arc::new([2.0, 3.0]);
    let p = front_to_back(tr.first_pieces_near(1.0, 1.5, 5.0));
    assert_eq!(
        p,
        vec![
            (1.0, 1.5),
            (1.5, 2.0),
            (2.0, 2.5),
            (2.5, 3.0),
            (3.0, 4.5),
            (4.5, 5.0)
        ]
    );
}
