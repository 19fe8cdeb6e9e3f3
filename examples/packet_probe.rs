use gradtrace::accel::Accel;
use gradtrace::math::{Ray, Vec3};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = gradtrace::scene::load(std::path::Path::new(&args[1])).unwrap();
    let spread: f32 = args[2].parse().unwrap();
    let dspread: f32 = args[3].parse().unwrap();
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let (lo, hi) = accel.bounds().unwrap();
    let mut s = 0x9e3779b97f4a7c15u64;
    let mut r = move || {
        s ^= s >> 12;
        s ^= s << 25;
        s ^= s >> 27;
        ((s.wrapping_mul(0x2545F4914F6CDD1D) >> 40) as f32) / (1u64 << 24) as f32
    };
    let n = 200_000 / 8;
    let mut packets = Vec::new();
    for _ in 0..n {
        let c = lo + (hi - lo) * Vec3::new(r(), r(), r()) * 0.98 + (hi - lo) * 0.01;
        let base = loop {
            let v = Vec3::new(r() * 2.0 - 1.0, r() * 2.0 - 1.0, r() * 2.0 - 1.0);
            if v.length_squared() <= 1.0 && v.length_squared() > 1e-4 {
                break v.normalize();
            }
        };
        let rays: [Ray; 8] = std::array::from_fn(|_| {
            let o = c + Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * spread;
            let d = loop {
                let v = Vec3::new(r() * 2.0 - 1.0, r() * 2.0 - 1.0, r() * 2.0 - 1.0);
                if v.length_squared() <= 1.0 && v.length_squared() > 1e-4 {
                    break (base + v * dspread).normalize();
                }
            };
            let mut ray = Ray::new(o, d);
            ray.t_max = 0.5;
            ray
        });
        packets.push(rays);
    }
    for round in 0..3 {
        let t = Instant::now();
        let mut h1 = 0;
        for p in &packets {
            for ray in p {
                let mut q = *ray;
                q.t_max = f32::INFINITY;
                h1 += accel.intersect(&q).is_some() as u32;
            }
        }
        let single_c = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut h2 = 0;
        for p in &packets {
            let q = p.map(|mut x| {
                x.t_max = f32::INFINITY;
                x
            });
            h2 += accel
                .intersect8(&q, 0xff)
                .iter()
                .filter(|h| h.is_some())
                .count() as u32;
        }
        let packet_c = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut o1 = 0;
        for p in &packets {
            for ray in p {
                o1 += accel.occluded(ray) as u32;
            }
        }
        let single_o = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut o2 = 0;
        for p in &packets {
            o2 += accel.occluded8(p, 0xff).count_ones();
        }
        let packet_o = t.elapsed().as_secs_f64();
        let m = (n * 8) as f64 / 1e6;
        println!("round {round}: closest single {:.2} packet {:.2} Mrays/s ({h1}/{h2}); any single {:.2} packet {:.2} ({o1}/{o2})",
            m / single_c, m / packet_c, m / single_o, m / packet_o);
    }
}
