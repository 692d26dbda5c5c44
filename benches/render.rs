//! Renderer speed: rays per second through the Cornell box (primary ray, shading, shadow ray).
//!
//! - `image_64spp`: the whole 64x64 image at 64 rays per pixel (262 144 rays) with padded MJ, on the
//!   rayon pool (all cores; run on the 2-core machine);
//! - `pixel_rays_1thread`: 65 536 rays of one back-wall pixel on one thread (no sampler cost).
//!
//! Criterion reports the throughput in rays (elements) per second. The reference image's render time
//! is printed by `anisospec render --reference`.

use anisospec::render::image::{estimate_pixel, render_image};
use anisospec::render::Scene;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;

fn rays(c: &mut Criterion) {
    let scene = Scene::load(None).expect("built-in scene");
    let sampler = anisospec::samplers::build("padded-mj", 4).expect("padded-mj");
    let hidden = indicatif::ProgressBar::hidden();
    let mut g = c.benchmark_group("render");
    g.sample_size(10);
    let spp = 64;
    g.throughput(Throughput::Elements(
        (scene.width() * scene.height() * spp) as u64,
    ));
    g.bench_function("image_64spp", |b| {
        b.iter(|| render_image(&scene, sampler.as_ref(), spp, 1, None, &hidden).expect("render"))
    });
    let n = 1 << 16;
    let points: Vec<f64> = (0..n)
        .flat_map(|i| {
            let t = (i as f64 + 0.5) / n as f64;
            [
                t,
                (t * 7.0).fract(),
                (t * 31.0).fract(),
                (t * 127.0).fract(),
            ]
        })
        .collect();
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("pixel_rays_1thread", |b| {
        b.iter(|| estimate_pixel(&scene, 20, 20, black_box(&points)))
    });
    g.finish();
}

criterion_group!(benches, rays);
criterion_main!(benches);
