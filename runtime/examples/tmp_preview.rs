// Temporary: CPU preview of a scene (shading x ground-truth visibility).
use glam::{Vec3, Vec4};
use sshc_runtime::scene::Scene;
use sshc_runtime::visibility::Visibility;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = Scene::load(&args[1]).unwrap_or_else(|e| panic!("{e}"));
    let out = &args[2];
    let samples: u32 = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(4);
    let vis = Visibility::new(&scene);
    let (w, h) = scene.camera_size();
    let inv = scene.camera_view_proj().inverse();
    let light = &scene.lights[0];
    let t0 = std::time::Instant::now();
    let mut points = vec![Vec3::NAN; (w * h) as usize];
    let mut normals = vec![Vec3::ZERO; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let ndc_x = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
            let ndc_y = 1.0 - (y as f32 + 0.5) / h as f32 * 2.0;
            let p0 = inv * Vec4::new(ndc_x, ndc_y, 0.0, 1.0);
            let p1 = inv * Vec4::new(ndc_x, ndc_y, 1.0, 1.0);
            let (p0, p1) = (p0.truncate() / p0.w, p1.truncate() / p1.w);
            let d = (p1 - p0).normalize();
            if let Some((t, tri)) = vis.closest_hit(p0, d, (p1 - p0).length()) {
                let i = (y * w + x) as usize;
                points[i] = p0 + d * t;
                let tr = scene.triangles()[tri];
                let mut n = (tr[1] - tr[0]).cross(tr[2] - tr[0]).normalize();
                if n.dot(d) > 0.0 {
                    n = -n;
                }
                normals[i] = n;
            }
        }
    }
    let v = vis.visible_fractions(&points, &normals, light, samples);
    eprintln!("{} px, {:?}", points.len(), t0.elapsed());
    let mut img = image::RgbImage::new(w, h);
    for (i, p) in points.iter().enumerate() {
        let px = if p.is_finite() {
            let l = match light.center() {
                Some(c) => (c - *p).normalize(),
                None => light.direction().unwrap(),
            };
            let s = 0.15 + 0.85 * normals[i].dot(l).max(0.0) * v[i];
            let pen = v[i] > 0.0 && v[i] < 1.0;
            [(s * 255.0) as u8, (s * 255.0) as u8, if pen { 255 } else { (s * 255.0) as u8 }]
        } else {
            [40, 40, 80]
        };
        img.put_pixel(i as u32 % w, i as u32 / w, image::Rgb(px));
    }
    img.save(out).unwrap();
}
