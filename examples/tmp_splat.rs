use std::time::Instant;
use voxless::*;
fn main() {
    let d = "/work/shared/data/sph-dam-break/npy_01000";
    let p = voxless::io::read_npy(std::path::Path::new(&format!("{d}/positions.npy"))).unwrap();
    let h = voxless::io::read_npy(std::path::Path::new(&format!("{d}/h.npy"))).unwrap();
    let m = voxless::io::read_npy(std::path::Path::new(&format!("{d}/mass.npy"))).unwrap();
    let pf: Vec<f32> = p.data.iter().map(|&x| x as f32).collect();
    let pos: Vec<Vec3> = pf.chunks(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
    let arrays = ParticleArrays {
        positions: pos,
        radii: Some(h.data.iter().map(|&x| x as f32).collect()),
        weights: Some(m.data.iter().map(|&x| x as f32).collect()),
        ..Default::default()
    };
    for _ in 0..8 {
        let _ = AnyVolume::from_particles(
            arrays.clone(),
            &ParticlesDesc {
                kernel: Some(KernelName::CubicSpline),
                ..Default::default()
            },
        )
        .unwrap();
    }
    let t = Instant::now();
    let l = AnyVolume::from_particles(
        arrays.clone(),
        &ParticlesDesc {
            kernel: Some(KernelName::CubicSpline),
            ..Default::default()
        },
    )
    .unwrap();
    println!("build {:?}", t.elapsed());
    let t = Instant::now();
    let l = AnyVolume::from_particles(
        arrays,
        &ParticlesDesc {
            kernel: Some(KernelName::CubicSpline),
            ..Default::default()
        },
    )
    .unwrap();
    println!("build {:?}", t.elapsed());
    let AnyVolume::Particles(v) = &l.volume else {
        panic!()
    };
    let view = ProjectionView::new(
        &ProjectionDesc {
            normal: Some([1.0, 0.5, 0.7]),
            width: Some([4.0, 4.0]),
            ..Default::default()
        },
        &l.volume.bounds(),
        &l.frame,
    )
    .unwrap();
    for _ in 0..2 {
        let c = Control::new();
        let t = Instant::now();
        let a = voxless::render::project(&**v, &view.camera, 200, 200, &c).unwrap();
        let t1 = t.elapsed();
        let t = Instant::now();
        let b = a.clone(); for _ in 0..20 { let _ = voxless::render::project(&**v, &view.camera, 800, 800, &c).unwrap(); }
        let t2 = t.elapsed();
        println!(
            "fast {t1:?} slow {t2:?} {} {}",
            a.iter().sum::<f32>(),
            b.iter().sum::<f32>()
        );
    }
}
