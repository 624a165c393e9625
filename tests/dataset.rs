//! `rendernet dataset` and its reader: the same seed gives the same bytes, train and test
//! never share a shape, what the reader returns is what was generated (grids, poses, lights,
//! rendered targets), and malformed manifests or shards fail with errors naming the file.
//! Small sizes (R = 16, S = 32, a handful of shapes) keep it quick on lavapipe.

use rendernet::Gpu;
use rendernet::data::{
    self, Dataset, GenerateOptions, Shapes, Split,
    generate::{sample_poses, shape_seed},
};
use rendernet::reference::{Light, Options, RayMarcher, Shader, View};
use rendernet::voxel::shapes::chair;
use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::OnceLock;

fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| Gpu::new().expect("a GPU or lavapipe adapter"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rendernet-dataset-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// 5 chairs x 3 views, test fraction 0.3: ceil(1.5) = 2 test shapes, 9 + 6 samples.
fn opts(seed: u64, shader: Shader) -> GenerateOptions {
    GenerateOptions {
        shapes: Shapes::Chairs,
        shader,
        count: 5,
        views: 3,
        res: 16,
        truth_res: 32,
        input_supersample: 1,
        image: 32,
        seed,
        test_fraction: 0.3,
        radius: rendernet::data::generate::PAPER_RADII,
        supersample: 1,
        ao_rays: 64,
        colour: false,
        real_dir: PathBuf::from("datasets/real"),
    }
}

/// The phong dataset every test reads, generated once.
fn phong_dir() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = tmp("phong");
        data::generate(gpu(), &opts(7, Shader::Phong), &d, |_, _| {}).unwrap();
        d
    })
}

/// Every file of a directory, sorted by name, with its bytes.
fn files(dir: &PathBuf) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().to_string(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

fn fnv1a(b: &[u8]) -> u64 {
    b.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &x| {
        (h ^ x as u64).wrapping_mul(0x100_0000_01b3)
    })
}

#[test]
fn same_seed_gives_same_bytes() {
    let again = tmp("again");
    data::generate(gpu(), &opts(7, Shader::Phong), &again, |_, _| {}).unwrap();
    let (a, b) = (files(phong_dir()), files(&again));
    let names: Vec<_> = a.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "manifest.json",
            "test-00000.safetensors",
            "train-00000.safetensors"
        ]
    );
    for ((na, ba), (nb, bb)) in a.iter().zip(&b) {
        assert_eq!(na, nb);
        assert_eq!(
            fnv1a(ba),
            fnv1a(bb),
            "{na} differs between two runs with the same seed"
        );
    }
    // And the seed matters.
    let other = tmp("other-seed");
    data::generate(gpu(), &opts(8, Shader::Phong), &other, |_, _| {}).unwrap();
    assert_ne!(
        fnv1a(&files(&other)[2].1),
        fnv1a(&a[2].1),
        "seed 8 gave seed 7's train shard"
    );
}

#[test]
fn train_and_test_share_no_shape() {
    let ds = Dataset::open(phong_dir()).unwrap();
    let ids = |s: Split| -> Vec<u32> {
        let v = ds.split(s);
        (0..v.len()).map(|i| v.get(i).unwrap().shape_id).collect()
    };
    let (train, test) = (ids(Split::Train), ids(Split::Test));
    assert_eq!(train, [0, 0, 0, 1, 1, 1, 2, 2, 2]);
    assert_eq!(test, [3, 3, 3, 4, 4, 4]);
    let a: BTreeSet<_> = train.into_iter().collect();
    assert!(a.is_disjoint(&test.into_iter().collect()));
}

#[test]
fn reader_returns_what_was_generated() {
    let ds = Dataset::open(phong_dir()).unwrap();
    let m = &ds.manifest;
    assert_eq!(
        (m.res, m.truth_res, m.image, m.views, m.seed),
        (16, 32, 32, 3, 7)
    );
    assert_eq!((m.train.count, m.test.count), (9, 6));
    let test = ds.split(Split::Test);
    let s = test.get(4).unwrap(); // shape 4, view 1
    assert_eq!(s.shape_id, 4);
    // Grid: the chair's own 16^3 rasterisation, exactly (occupancy is 0/1, so u8 is lossless).
    let seed = shape_seed(7, 4);
    assert_eq!(s.grid, chair(seed).to_grid(16).unwrap());
    // Pose and light: the generator's draws, and within the paper's ranges.
    let (v, l) = sample_poses(seed, 3, rendernet::data::generate::PAPER_RADII)[1];
    assert_eq!(
        [s.view.azimuth, s.view.elevation, s.view.radius],
        v.map(f64::from)
    );
    assert_eq!(
        [s.light.azimuth, s.light.elevation],
        [l[0] as f64, l[1] as f64]
    );
    assert_eq!(s.light.colour, [1.0; 3]);
    assert!((0.0..360.0).contains(&s.view.azimuth) && (10.0..170.0).contains(&s.view.elevation));
    assert!((3.0..6.3).contains(&s.view.radius) && (20.0..160.0).contains(&s.light.elevation));
    // Images: names, shapes, and the reference renderer's output of the 32^3 truth grid,
    // to within u8 rounding (half a level, plus float slack).
    let shapes: Vec<_> = s
        .images
        .iter()
        .map(|(k, im)| (k.as_str(), im.shape()))
        .collect();
    assert_eq!(
        shapes,
        [
            ("albedo", [1, 32, 32]),
            ("mask", [1, 32, 32]),
            ("normal", [3, 32, 32]),
            ("phong", [3, 32, 32])
        ]
    );
    let renderer = RayMarcher::new(gpu()).with_options(Options {
        supersample: 1,
        ..Options::default()
    });
    let truth = chair(seed).to_grid(32).unwrap();
    let light = Light {
        azimuth: s.light.azimuth,
        elevation: s.light.elevation,
        ..Light::default()
    };
    let view = View { ..s.view };
    for (name, shader) in [
        ("phong", Shader::Phong),
        ("normal", Shader::Normal),
        ("mask", Shader::Mask),
    ] {
        let want = renderer
            .render(gpu(), &truth, &view, &light, shader, 32)
            .unwrap();
        let got = &s.images[name];
        let err = want
            .data
            .iter()
            .zip(&got.data)
            .map(|(a, b)| (a.clamp(0.0, 1.0) - b).abs())
            .fold(0.0, f32::max);
        assert!(err <= 0.5 / 255.0 + 1e-6, "{name}: max error {err}");
    }
    let covered = s.images["mask"].data.iter().filter(|&&x| x > 0.5).count();
    assert!(covered > 20, "the chair covers only {covered} pixels");
    // Second shard cache slot: alternate splits and come back.
    let t0 = ds.split(Split::Train).get(0).unwrap();
    assert_eq!(t0.shape_id, 0);
    assert_eq!(test.get(4).unwrap().images["phong"], s.images["phong"]);
    assert!(test.get(6).is_err());
}

#[test]
fn other_shaders_store_one_image_tensor() {
    let d = tmp("depth");
    let mut o = opts(3, Shader::Depth);
    o.count = 2;
    o.shapes = Shapes::Mixed;
    data::generate(gpu(), &o, &d, |_, _| {}).unwrap();
    let ds = Dataset::open(&d).unwrap();
    assert_eq!(ds.manifest.shader, "depth");
    let s = ds.split(Split::Train).get(0).unwrap();
    assert_eq!(s.images.keys().collect::<Vec<_>>(), ["image"]);
    assert_eq!(s.images["image"].shape(), [1, 32, 32]);
    assert_eq!(ds.split(Split::Test).len(), 3);
    // The network of a shader other than Phong takes no light: every view is lit by the
    // default light (toon targets depend on it).
    let d = Light::default();
    for i in 0..ds.split(Split::Train).len() {
        let l = ds.split(Split::Train).get(i).unwrap().light;
        assert_eq!((l.azimuth, l.elevation), (d.azimuth as f32 as f64, d.elevation as f32 as f64), "sample {i}");
    }
}

/// A copy of the phong dataset to damage.
fn copy(name: &str) -> PathBuf {
    let d = tmp(name);
    std::fs::create_dir_all(&d).unwrap();
    for (n, b) in files(phong_dir()) {
        std::fs::write(d.join(n), b).unwrap();
    }
    d
}

fn open_err(d: &PathBuf) -> String {
    match Dataset::open(d) {
        Ok(_) => panic!("{} opened despite the damage", d.display()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn malformed_manifest_names_file_and_field() {
    let d = copy("bad-manifest");
    let mpath = d.join("manifest.json");
    let good = std::fs::read_to_string(&mpath).unwrap();
    let cases = [
        ("{ not json", "not valid JSON"),
        (
            &good.replace("rendernet-dataset-1", "rendernet-dataset-9"),
            "`format`",
        ),
        (&good.replace("\"res\": 16", "\"res\": \"16\""), "`res`"),
        (
            &good.replace("\"count\": 9", "\"count\": 300"),
            "`train.shards`",
        ),
        (
            &good.replace("\"shader\": \"phong\"", "\"shader\": \"gouraud\""),
            "`shader`",
        ),
        (&good.replace("\"kd\"", "\"kdd\""), "`light.kd`"),
    ];
    for (text, field) in cases {
        std::fs::write(&mpath, text).unwrap();
        let e = open_err(&d);
        assert!(
            e.contains("manifest.json") && e.contains(field),
            "error {e:?} should name manifest.json and {field}"
        );
    }
    std::fs::remove_file(&mpath).unwrap();
    assert!(open_err(&d).contains("manifest.json"));
}

#[test]
fn malformed_shard_names_file_and_tensor() {
    // Truncated: the header describes more bytes than the file has.
    let d = copy("bad-shard");
    let p = d.join("train-00000.safetensors");
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, &bytes[..bytes.len() - 100]).unwrap();
    let e = open_err(&d);
    assert!(
        e.contains("train-00000.safetensors") && e.contains("bytes"),
        "{e}"
    );
    // Garbage header length.
    std::fs::write(&p, [0xffu8; 16]).unwrap();
    assert!(open_err(&d).contains("train-00000.safetensors"));
    // A manifest claiming another resolution: every tensor's shape is now wrong.
    let d = copy("bad-res");
    let mpath = d.join("manifest.json");
    let m = std::fs::read_to_string(&mpath)
        .unwrap()
        .replace("\"res\": 16", "\"res\": 17");
    std::fs::write(&mpath, m).unwrap();
    let e = open_err(&d);
    assert!(
        e.contains("-00000.safetensors") && e.contains("`grids`") && e.contains("shape"),
        "{e}"
    );
    // Missing shard file.
    let d = copy("missing-shard");
    std::fs::remove_file(d.join("test-00000.safetensors")).unwrap();
    assert!(open_err(&d).contains("test-00000.safetensors"));
}

// Runs the binary, which needs the `cli` feature.
#[cfg(feature = "cli")]
#[test]
fn cli_writes_a_dataset_and_explains_missing_real_meshes() {
    let d = tmp("cli");
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_rendernet"))
            .arg("dataset")
            .args(args)
            .output()
            .unwrap()
    };
    let out = run(&[
        "--count",
        "2",
        "--views",
        "2",
        "--res",
        "8",
        "--image",
        "16",
        "--shader",
        "mask",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("2 train + 2 test samples"));
    assert_eq!(Dataset::open(&d).unwrap().manifest.shader, "mask");
    let empty = tmp("no-meshes");
    std::fs::create_dir_all(&empty).unwrap();
    let out = run(&[
        "--shapes",
        "real",
        "--real-dir",
        empty.to_str().unwrap(),
        "--count",
        "3",
        "--out",
        d.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("fetch_real.sh"),
        "{err}"
    );
}

/// `ao_rays` sets the ambient-occlusion rays of AO targets: 16 rays give the same picture
/// as 64 up to sampling (close on average, not identical), the manifest records the count,
/// and a count that is not a perfect square is refused by name.
#[test]
fn ao_targets_take_their_ray_count() {
    let images = |rays: u32| {
        let d = tmp(&format!("ao{rays}"));
        let mut o = opts(4, Shader::AmbientOcclusion);
        o.count = 1;
        o.views = 1;
        o.test_fraction = 0.0;
        o.ao_rays = rays;
        data::generate(gpu(), &o, &d, |_, _| {}).unwrap();
        let ds = Dataset::open(&d).unwrap();
        assert_eq!(ds.manifest.ao_rays, rays);
        ds.split(Split::Train).get(0).unwrap().images["image"].data.clone()
    };
    let (coarse, fine) = (images(16), images(64));
    let diff = coarse.iter().zip(&fine).map(|(a, b)| (a - b).abs()).sum::<f32>() / fine.len() as f32;
    assert!(diff > 0.0 && diff < 0.05, "mean |AO16 - AO64| = {diff}");
    let mut o = opts(4, Shader::AmbientOcclusion);
    o.ao_rays = 15;
    let err = data::generate(gpu(), &o, &tmp("ao15"), |_, _| {}).unwrap_err().to_string();
    assert!(err.contains("--ao-rays 15"), "{err}");
}

/// `colour`: shards carry the input grid's RGB (`colours`), the Phong albedo target is RGB,
/// and what the reader returns is what the generator painted: the input grid's colours equal
/// the shape's paint at the same resolution, and the albedo image is not grey. Real meshes
/// (unpainted) are refused by flag name.
#[test]
fn coloured_datasets_carry_the_paint() {
    let d = tmp("colour");
    let o = GenerateOptions { colour: true, ..opts(21, Shader::Phong) };
    data::generate(gpu(), &o, &d, |_, _| {}).unwrap();
    let ds = Dataset::open(&d).unwrap();
    assert!(ds.manifest.colour);
    let s = ds.split(Split::Train).get(0).unwrap();
    let seed = rendernet::data::generate::shape_seed(o.seed, 0);
    let want = rendernet::voxel::Family::Chair.generate(seed).to_coloured_grid(o.res, seed).unwrap();
    let (got, want) = (s.grid.colour().expect("a coloured grid"), want.colour().unwrap());
    let occupied: Vec<usize> = (0..s.grid.len()).filter(|&i| s.grid.occupancy()[i] > 0.5).collect();
    assert!(!occupied.is_empty());
    for &i in &occupied {
        for c in 0..3 {
            let (g, w) = (got[c * s.grid.len() + i], want[c * s.grid.len() + i]);
            assert!((g - w).abs() <= 0.5 / 255.0 + 1e-6, "voxel {i} channel {c}: {g} stored, {w} painted");
        }
    }
    let albedo = &s.images["albedo"];
    assert_eq!(albedo.channels, 3);
    let px = albedo.size * albedo.size;
    let coloured = (0..px).filter(|&i| (albedo.data[i] - albedo.data[px + i]).abs() > 0.1 || (albedo.data[i] - albedo.data[2 * px + i]).abs() > 0.1).count();
    assert!(coloured > 10, "only {coloured} albedo pixels are not grey");
    let real = GenerateOptions { shapes: Shapes::Real, ..o };
    let err = data::generate(gpu(), &real, &tmp("colour-real"), |_, _| {}).unwrap_err().to_string();
    assert!(err.contains("--colour") && err.contains("real"), "{err}");
}

/// `input_supersample`: the input grids hold each voxel's fraction inside the shape (the
/// shape's `to_grid_supersampled`, to u8 rounding), so surface voxels lie strictly between 0
/// and 1, while the targets stay those of the binary dataset; the manifest records the factor.
/// The default dataset's grids are binary and its manifest says 1.
#[test]
fn supersampled_inputs_hold_the_fraction_inside() {
    let d = tmp("soft");
    data::generate(gpu(), &GenerateOptions { input_supersample: 4, ..opts(7, Shader::Phong) }, &d, |_, _| {}).unwrap();
    let (soft, binary) = (Dataset::open(&d).unwrap(), Dataset::open(phong_dir()).unwrap());
    assert_eq!((soft.manifest.input_supersample, binary.manifest.input_supersample), (4, 1));
    let (s, b) = (soft.split(Split::Test).get(4).unwrap(), binary.split(Split::Test).get(4).unwrap());
    let want = chair(shape_seed(7, 4)).to_grid_supersampled(16, 4).unwrap();
    let err = s.grid.occupancy().iter().zip(want.occupancy()).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
    assert!(err <= 0.5 / 255.0 + 1e-6, "soft grid differs from to_grid_supersampled by {err}");
    let partial = s.grid.occupancy().iter().filter(|&&v| v > 0.0 && v < 1.0).count();
    assert!(partial > 50, "only {partial} partial voxels");
    assert!(b.grid.occupancy().iter().all(|&v| v == 0.0 || v == 1.0), "the default grids are not binary");
    assert_eq!(s.images, b.images, "the targets depend on the input's sampling");
    let _ = std::fs::remove_dir_all(&d);
}
