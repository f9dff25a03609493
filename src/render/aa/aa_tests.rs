use super::*;

#[test]
fn modes_parse() {
    assert_eq!(Aa::parse("none"), Ok(Aa::None));
    assert_eq!(Aa::parse("grid:4"), Ok(Aa::Grid(4)));
    assert!(matches!(Aa::parse("iaa"), Ok(Aa::Iaa { depth: 2, .. })));
    assert_eq!(Aa::parse("grid:0"), Err(AaError::GridOutOfRange(0)));
    assert!(matches!(
        Aa::parse("grid:x"),
        Err(AaError::NotANumber { .. })
    ));
    assert_eq!(
        Aa::parse("ssaa").map_err(|e| e.to_string()),
        Err("anti-aliasing `ssaa` is not none, iaa or grid:N".to_string())
    );
}

#[test]
fn sampling_levels_follow_the_depth() {
    use Sampling::*;
    let levels = |d: u32| [Base, Shading, Covered, Full].map(|s| s.level(d));
    assert_eq!(levels(0), [0, 0, 0, 0]);
    assert_eq!(levels(1), [0, 1, 1, 1]);
    assert_eq!(levels(2), [0, 1, 1, 2]);
    assert_eq!(levels(3), [0, 1, 2, 3]);
    assert_eq!(levels(4), [0, 1, 3, 4]);
}

#[test]
fn normalized_box_holds_every_unit_vector() {
    let g = [
        Interval::new(0.5, 2.0),
        Interval::new(-1.0, 0.25),
        Interval::new(3.0, 3.5),
    ];
    let n = normalize_box(&g).unwrap();
    for a in [0.5, 1.0, 2.0] {
        for b in [-1.0, 0.0, 0.25] {
            for c in [3.0f64, 3.5] {
                let l = (a * a + b * b + c * c).sqrt();
                for (i, v) in [a / l, b / l, c / l].iter().enumerate() {
                    assert!(n[i].contains(*v), "{i} {v} {:?}", n[i]);
                }
            }
        }
    }
    let z = [Interval::new(-1.0, 1.0); 3];
    assert!(normalize_box(&z).is_none());
}
