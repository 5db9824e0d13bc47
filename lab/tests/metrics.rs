//! Metrics against the ground truth on hand-made arrays whose answers are known.

use glam::Vec3;
use sshc_lab::metrics::{self, MASKED_GREY};
use sshc_lab::scene::Light;

const EPS: f64 = 1e-9;

#[test]
fn rms_and_max_in_0_255_units() {
    // Errors 0, +0.1, -0.2, 0.4 (in 0..1): squares 0, 0.01, 0.04, 0.16, mean 0.0525.
    let truth = [0.5, 0.5, 0.5, 0.25];
    let estimate = [0.5, 0.6, 0.3, 0.65];
    let all = [true; 4];
    let s = metrics::error_stats(&estimate, &truth, &all).unwrap();
    assert_eq!(s.pixels, 4);
    assert!((s.rms - 255.0 * 0.0525f64.sqrt()).abs() < 1e-4, "{s:?}");
    assert!((s.max - 255.0 * 0.4).abs() < 1e-4, "{s:?}");
    assert!((s.mean - 255.0 * 0.3 / 4.0).abs() < 1e-4, "{s:?}");
    // The mask leaves pixels out.
    let s = metrics::error_stats(&estimate, &truth, &[true, true, false, false]).unwrap();
    assert_eq!(s.pixels, 2);
    assert!((s.rms - 255.0 * (0.01f64 / 2.0).sqrt()).abs() < 1e-4, "{s:?}");
    assert!((s.max - 25.5).abs() < 1e-4, "{s:?}");
    // No pixel: zeros.
    let s = metrics::error_stats(&estimate, &truth, &[false; 4]).unwrap();
    assert_eq!((s.pixels, s.rms, s.max), (0, 0.0, 0.0));
    // Exact: a perfect estimate.
    let s = metrics::error_stats(&truth, &truth, &all).unwrap();
    assert!(s.rms < EPS && s.max < EPS);
}

#[test]
fn a_non_finite_visibility_is_the_largest_error_and_counted() {
    let s = metrics::error_stats(&[f32::NAN, 1.0, f32::INFINITY], &[0.0, 1.0, 1.0], &[true; 3]).unwrap();
    assert_eq!(s.non_finite, 2);
    assert_eq!(s.max, 255.0);
    assert!((s.rms - 255.0 * (2.0f64 / 3.0).sqrt()).abs() < 1e-9);
}

#[test]
fn sizes_must_agree() {
    let e = metrics::error_stats(&[0.0; 3], &[0.0; 4], &[true; 4]).unwrap_err();
    assert!(e.0.contains("3 values against 4"), "{e}");
    assert!(metrics::error_image(&[0.0; 4], &[0.0; 4], None, 3, 1, 8.0).is_err());
    assert!(metrics::mean_frame_change(&[vec![0.0; 2], vec![0.0; 3]], &[true; 2]).is_err());
}

#[test]
fn penumbra_is_strictly_between_0_and_1_among_masked_pixels() {
    let truth = [0.0, 1e-6, 0.5, 0.999_999, 1.0, 0.5];
    let mask = [true, true, true, true, true, false];
    let p = metrics::penumbra(&truth, &mask).unwrap();
    assert_eq!(p, vec![false, true, true, true, false, false]);
    // Accuracy: the facing figure over all masked pixels, penumbra over its share.
    let estimate = [0.0, 0.0, 1.0, 1.0, 1.0, 0.0];
    let acc = metrics::accuracy(&estimate, &truth, &mask).unwrap();
    assert_eq!(acc.facing.pixels, 5);
    assert_eq!(acc.penumbra.pixels, 3);
    assert!((acc.penumbra.max - 127.5).abs() < 1e-6, "{acc:?}");
    // The penumbra's errors are 1e-6, 0.5, 1e-6: RMS = 0.5 / sqrt 3 (to 1e-6).
    assert!((acc.penumbra.rms - 255.0 * 0.5 / 3f64.sqrt()).abs() < 1e-3, "{acc:?}");
    // The lit and umbra pixels are exact, so the facing RMS is diluted: 0.5 / sqrt 5.
    assert!((acc.facing.rms - 255.0 * 0.5 / 5f64.sqrt()).abs() < 1e-3, "{acc:?}");
}

#[test]
fn facing_uses_the_light_centre_or_its_direction() {
    let positions = [Vec3::ZERO, Vec3::ZERO, Vec3::new(5.0, 0.0, 0.0), Vec3::NAN, Vec3::ZERO];
    let normals = [Vec3::Y, -Vec3::Y, Vec3::Y, Vec3::Y, Vec3::NAN];
    let point = Light::Point {
        position: Vec3::new(0.0, 2.0, 0.0),
    };
    assert_eq!(
        metrics::facing_light(&positions, &normals, &point).unwrap(),
        vec![true, false, true, false, false]
    );
    // Facing a wall at x = 5 from the side: a light below the receiver's plane.
    let low = Light::Sphere {
        center: Vec3::new(10.0, -1.0, 0.0),
        radius: 0.5,
    };
    assert_eq!(
        metrics::facing_light(&positions, &normals, &low).unwrap(),
        vec![false, true, false, false, false]
    );
    let sun = Light::DistantDisk {
        direction: Vec3::new(0.0, 1.0, 0.0),
        angle_degrees: 1.0,
    };
    assert_eq!(
        metrics::facing_light(&positions, &normals, &sun).unwrap(),
        vec![true, false, true, false, false]
    );
}

#[test]
fn error_colours_are_blue_white_red() {
    let range = 16.0;
    let white = metrics::error_colour(0.0, range);
    let red = metrics::error_colour(range, range);
    let blue = metrics::error_colour(-range, range);
    // colorous's continuous RdBu (a B-spline through ColorBrewer's 11 classes): its centre
    // is (241, 239, 237), near white; its ends are dark red and dark blue.
    let rgb = |t: f64| {
        let c = colorous::RED_BLUE.eval_continuous(t);
        [c.r, c.g, c.b]
    };
    assert_eq!(white, rgb(0.5));
    assert!(
        white.iter().all(|&c| c >= 235) && white.iter().max().unwrap() - white.iter().min().unwrap() <= 6,
        "{white:?}"
    );
    assert_eq!(red, rgb(0.0));
    assert_eq!(blue, rgb(1.0));
    assert!(red[0] > 90 && red[1] < 10 && red[2] < 40, "{red:?}");
    assert!(blue[2] > 80 && blue[0] < 10 && blue[1] < 60, "{blue:?}");
    // Clamped beyond the range, symmetric in between.
    assert_eq!(metrics::error_colour(10.0 * range, range), red);
    assert_eq!(metrics::error_colour(-10.0 * range, range), blue);
    let half_red = metrics::error_colour(range / 2.0, range);
    let half_blue = metrics::error_colour(-range / 2.0, range);
    assert!(
        half_red[0] > half_red[2] && half_blue[2] > half_blue[0],
        "{half_red:?} {half_blue:?}"
    );

    // An image with errors -1, 0, +1 (in 0..1, i.e. -255, 0, 255) at range 255, a masked
    // pixel, and a NaN (shown as the largest positive error).
    let truth = [1.0, 0.5, 0.0, 0.5, 0.5];
    let estimate = [0.0, 0.5, 1.0, 0.0, f32::NAN];
    let mask = [true, true, true, false, true];
    let img = metrics::error_image(&estimate, &truth, Some(&mask), 5, 1, 255.0).unwrap();
    assert_eq!(img.get_pixel(0, 0).0, blue);
    assert_eq!(img.get_pixel(1, 0).0, white);
    assert_eq!(img.get_pixel(2, 0).0, red);
    assert_eq!(img.get_pixel(3, 0).0, MASKED_GREY);
    assert_eq!(img.get_pixel(4, 0).0, red);
}

#[test]
fn the_error_range_rounds_the_largest_error_up() {
    let truth = [0.5f32; 3];
    let range = |e: f32| metrics::error_range(&[0.5, 0.5 + e, 0.5], &truth, &[true; 3]).unwrap();
    assert_eq!(range(0.0), 4.0);
    assert_eq!(range(3.0 / 255.0), 4.0);
    assert_eq!(range(5.0 / 255.0), 8.0);
    assert_eq!(range(100.0 / 255.0), 128.0);
    assert_eq!(range(0.5), 128.0);
    assert_eq!(range(0.5 + 1.0 / 255.0), 255.0);
}

#[test]
fn mean_frame_change_averages_absolute_steps_over_the_mask() {
    let frames = vec![vec![0.0, 0.5, 1.0], vec![0.1, 0.5, 0.0], vec![0.0, 0.7, 0.0]];
    let mask = [true, true, false];
    // Steps over the mask: |0.1|, 0, |-0.1|, |0.2| -> mean 0.1 -> 25.5.
    let m = metrics::mean_frame_change(&frames, &mask).unwrap();
    assert!((m - 25.5).abs() < 1e-5, "{m}");
    assert_eq!(metrics::mean_frame_change(&frames[..1], &mask).unwrap(), 0.0);
    assert_eq!(metrics::mean_frame_change(&frames, &[false; 3]).unwrap(), 0.0);
}

#[test]
fn a_non_finite_or_absurd_visibility_is_refused_before_any_figure() {
    let n = 64 * 64;
    let mask = vec![true; n];
    let mut vis = vec![0.5f32; n];
    assert!(metrics::check_visibility("v", &vis, &mask).is_ok());
    vis[100] = f32::NAN;
    vis[200] = 1e30;
    let err = metrics::check_visibility("the technique's visibility", &vis, &mask).unwrap_err();
    assert!(err.0.contains("the technique's visibility: 2 pixel(s)"), "{err}");
    assert!(err.0.contains("pixel 100, value NaN"), "{err}");
    vis[100] = f32::INFINITY;
    assert!(metrics::check_visibility("v", &vis, &mask).is_err());
    // Outside the mask (background pixels) anything goes.
    let mut masked = mask.clone();
    masked[100] = false;
    masked[200] = false;
    assert!(metrics::check_visibility("v", &vis, &masked).is_ok());
}

/// The region split: lit (truth 1), penumbra and umbra (truth 0) partition the facing
/// pixels, and the signs tell acne (a lit pixel darkened: negative) from a leak (an umbra
/// pixel brightened: positive).
#[test]
fn regions_split_the_facing_pixels_and_keep_the_sign() {
    // truth: lit, lit, penumbra, umbra, umbra, lit but not facing
    let truth = [1.0, 1.0, 0.5, 0.0, 0.0, 1.0];
    let facing = [true, true, true, true, true, false];
    // acne on the first lit pixel (-0.2), a leak in the first umbra pixel (+0.4)
    let est = [0.8, 1.0, 0.5, 0.4, 0.0, 0.0];
    let (lit, umbra) = metrics::regions(&truth, &facing).unwrap();
    assert_eq!(lit, [true, true, false, false, false, false]);
    assert_eq!(umbra, [false, false, false, true, true, false]);
    let a = metrics::accuracy(&est, &truth, &facing).unwrap();
    assert_eq!((a.lit.pixels, a.penumbra.pixels, a.umbra.pixels), (2, 1, 2));
    assert_eq!(a.lit.pixels + a.penumbra.pixels + a.umbra.pixels, a.facing.pixels);
    assert!((a.lit.mean - 255.0 * -0.1).abs() < 1e-4, "{a:?}");
    assert!((a.umbra.mean - 255.0 * 0.2).abs() < 1e-4, "{a:?}");
    assert!(a.penumbra.mean.abs() < EPS);
    let line = metrics::split_line(&a);
    assert!(line.contains("lit mean -25.50") && line.contains("umbra mean +51.00"), "{line}");
}
