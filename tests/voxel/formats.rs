//! binvox, safetensors and mesh file formats: round trips and malformed input.

use super::*;

#[test]
fn binvox_round_trip_is_exact() {
    for dims in [[32, 32, 32], [5, 7, 9]] {
        let bv = Binvox {
            grid: pattern_grid(dims),
            translate: [-0.123_456_7, 0.5, 1e-7],
            scale: 0.987_654_3,
        };
        let path = tmp(&format!("rt{}.binvox", dims[1]));
        bv.write(&path).unwrap();
        assert_eq!(Binvox::read(&path).unwrap(), bv);
    }
    // Long uniform runs must be split at 255.
    let full = Binvox::from_grid(VoxelGrid::new([20, 20, 20], vec![1.0; 8000]).unwrap());
    assert_eq!(Binvox::parse(&full.to_bytes(), "full").unwrap(), full);
}

#[test]
fn binvox_axis_convention_matches_spec() {
    // dims A=2 (x), B=3, C=4; spec index = x*B*C + z*C + y. Set file voxel x=1, z=1, y=2.
    let fi = 12 + 4 + 2;
    let mut bytes = b"#binvox 1\ndim 2 3 4\ntranslate 0 0 0\nscale 1\ndata\n".to_vec();
    bytes.extend([0, fi as u8, 1, 1, 0, (24 - fi - 1) as u8]);
    let g = Binvox::parse(&bytes, "axes.binvox").unwrap().grid;
    assert_eq!(g.dims(), [2, 4, 3], "[D, H, W] = [x, y, z] = [A, C, B]");
    assert_eq!(g.get(1, 2, 1), 1.0);
    assert_eq!(g.occupied_count(), 1);
    assert_eq!(Binvox::from_grid(g).to_bytes(), bytes);
}

#[test]
fn binvox_malformed_inputs_are_errors() {
    let header = "#binvox 1\ndim 4 4 4\ntranslate 0 0 0\nscale 1\ndata\n";
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("truncated", [header.as_bytes(), &[1, 10, 0]].concat()),
        ("overrun", [header.as_bytes(), &[1, 60, 0, 10]].concat()),
        ("value", [header.as_bytes(), &[7, 64]].concat()),
        ("magic", b"#notvox 1\ndim 4 4 4\ndata\n\x01\x40".to_vec()),
        ("nodata", b"#binvox 1\ndim 4 4 4\n".to_vec()),
        ("nodim", b"#binvox 1\ndata\n\x01\x40".to_vec()),
        ("baddim", b"#binvox 1\ndim 4 x 4\ndata\n\x01\x40".to_vec()),
        ("zerodim", b"#binvox 1\ndim 0 4 4\ndata\n".to_vec()),
        ("binary", vec![0xff; 5000]),
        ("empty", vec![]),
    ];
    for (name, bytes) in cases {
        let file = format!("{name}.binvox");
        err_naming(Binvox::parse(&bytes, &file), &file);
    }
    let msg = err_naming(
        Binvox::parse(b"#binvox 1\ndim 2000 2000 2000\ndata\n", "huge.binvox"),
        "huge.binvox",
    );
    assert!(msg.contains("limit"), "{msg}");
    let msg = err_naming(
        Binvox::parse(&[header.as_bytes(), &[1, 10]].concat(), "t.binvox"),
        "t.binvox",
    );
    assert!(msg.contains("truncated run-length data at byte"), "{msg}");
    err_naming(Binvox::read(tmp("missing.binvox")), "missing.binvox");
}

#[test]
fn safetensors_round_trip_and_validation() {
    let dims = [4, 5, 6];
    let plain = pattern_grid(dims);
    let colour: Vec<f32> = (0..3 * plain.len()).map(|i| i as f32 * 0.01).collect();
    let coloured = plain.clone().with_colour(colour).unwrap();
    for g in [plain, coloured] {
        let path = tmp("grid.safetensors");
        safetensors_io::write(&g, &path).unwrap();
        assert_eq!(safetensors_io::read(&path).unwrap(), g);
    }
    // u8 occupancy (the fixtures' form): exact for 0/1, within 1/510 for fractions.
    let frac = VoxelGrid::new([3, 4, 5], (0..60).map(|i| i as f32 / 59.0).collect()).unwrap();
    let bytes = safetensors_io::to_bytes_u8(&frac).unwrap();
    assert!(bytes.len() < safetensors_io::to_bytes(&frac).unwrap().len());
    let back = safetensors_io::from_bytes(&bytes, "u8.safetensors").unwrap();
    assert_eq!(back.dims(), [3, 4, 5]);
    assert!(back.occupancy().iter().zip(frac.occupancy()).all(|(a, b)| (a - b).abs() <= 1.0 / 510.0 + 1e-7));
    let binary = pattern_grid(dims);
    assert_eq!(safetensors_io::from_bytes(&safetensors_io::to_bytes_u8(&binary).unwrap(), "b").unwrap(), binary);

    use safetensors::{Dtype, tensor::TensorView};
    let encode = |tensors: Vec<(&str, Dtype, Vec<usize>)>| {
        let bufs: Vec<Vec<u8>> = tensors
            .iter()
            .map(|(_, dt, s)| vec![0u8; s.iter().product::<usize>() * dt.bitsize() / 8])
            .collect();
        let views: Vec<_> = tensors
            .iter()
            .zip(&bufs)
            .map(|((n, dt, s), b)| (*n, TensorView::new(*dt, s.clone(), b).unwrap()))
            .collect();
        safetensors::serialize(views, None).unwrap()
    };
    let bad = [
        ("rank", encode(vec![("occupancy", Dtype::F32, vec![4, 4])])),
        (
            "dtype",
            encode(vec![("occupancy", Dtype::F64, vec![2, 2, 2])]),
        ),
        (
            "colourshape",
            encode(vec![
                ("occupancy", Dtype::F32, vec![2, 2, 2]),
                ("colour", Dtype::F32, vec![3, 2, 2, 3]),
            ]),
        ),
        (
            "extra",
            encode(vec![
                ("occupancy", Dtype::F32, vec![2, 2, 2]),
                ("weights", Dtype::F32, vec![3]),
            ]),
        ),
        (
            "missing",
            encode(vec![("colour", Dtype::F32, vec![3, 2, 2, 2])]),
        ),
        (
            "huge",
            encode(vec![("occupancy", Dtype::F32, vec![1, 1, 2000])]),
        ),
    ];
    for (name, bytes) in bad {
        let file = format!("{name}.safetensors");
        err_naming(safetensors_io::from_bytes(&bytes, &file), &file);
    }
    let mut out_of_range = safetensors_io::to_bytes(&pattern_grid([2, 2, 2])).unwrap();
    let n = out_of_range.len();
    out_of_range[n - 4..].copy_from_slice(&2.0f32.to_le_bytes());
    let msg = err_naming(
        safetensors_io::from_bytes(&out_of_range, "range.safetensors"),
        "range.safetensors",
    );
    assert!(msg.contains("outside [0, 1]"), "{msg}");
    err_naming(
        safetensors_io::from_bytes(b"garbage", "junk.safetensors"),
        "junk.safetensors",
    );
}

const CUBE_OFF: &str = "OFF\n# unit cube\n8 6 12\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n\
    4 0 4 6 2\n4 1 3 7 5\n4 0 1 5 4\n4 2 6 7 3\n4 0 2 3 1\n4 4 5 7 6\n";

fn cube_ply_header(format: &str) -> String {
    format!(
        "ply\nformat {format} 1.0\ncomment test\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nelement face 6\nproperty list uchar int vertex_indices\nelement edge 1\nproperty int a\nend_header\n"
    )
}

fn cube_ply_binary() -> Vec<u8> {
    cube_ply_encoded(false)
}

fn cube_ply_encoded(big_endian: bool) -> Vec<u8> {
    let off = Mesh::parse_off(CUBE_OFF, "cube.off").unwrap();
    let order = |mut x: [u8; 4]| {
        if big_endian {
            x.reverse();
        }
        x
    };
    let format = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut b = cube_ply_header(format).into_bytes();
    for p in &off.positions {
        p.iter().for_each(|c| b.extend(order(c.to_le_bytes())));
        b.push(200); // the ignored colour property
    }
    for q in [
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 2, 3, 1],
        [4, 5, 7, 6],
    ] {
        b.push(4);
        q.iter()
            .for_each(|i: &i32| b.extend(order(i.to_le_bytes())));
    }
    b.extend(order(9i32.to_le_bytes()));
    b
}

#[test]
fn mesh_loaders_agree_on_a_cube() {
    let off = Mesh::parse_off(CUBE_OFF, "cube.off").unwrap();
    assert_eq!((off.positions.len(), off.triangles.len()), (8, 12));
    assert!(
        (off.signed_volume() - 1.0).abs() < 1e-6,
        "outward winding gives +1"
    );

    // OBJ: same cube, mixing index forms, negative indices and comments.
    let mut obj = String::from("# cube\no cube\n");
    for p in &off.positions {
        obj += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    obj +=
        "vt 0 0\nvn 0 0 1\nf 1/1 5/1 7/1 3/1\nf 2//1 4//1 8//1 6//1\nf 1/1/1 2/1/1 6/1/1 5/1/1\n";
    obj += "f -6 -2 -1 -5\nf 1 3 4 2\nf 5 6 8 7 # top\n";
    let obj = Mesh::parse_obj(&obj, "cube.obj").unwrap();
    assert_eq!(obj, off);

    let ascii_body = "0 0 0 1\n1 0 0 1\n0 1 0 1\n1 1 0 1\n0 0 1 1\n1 0 1 1\n0 1 1 1\n1 1 1 1\n\
        4 0 4 6 2\n4 1 3 7 5\n4 0 1 5 4\n4 2 6 7 3\n4 0 2 3 1\n4 4 5 7 6\n9\n";
    let ply_ascii = Mesh::parse_ply_bytes(
        format!("{}{ascii_body}", cube_ply_header("ascii")).as_bytes(),
        "cube.ply",
    );
    assert_eq!(ply_ascii.unwrap(), off);
    assert_eq!(
        Mesh::parse_ply_bytes(&cube_ply_binary(), "cube.ply").unwrap(),
        off
    );
    assert_eq!(
        Mesh::parse_ply_bytes(&cube_ply_encoded(true), "cube.ply").unwrap(),
        off
    );

    // Dispatch by extension through the file system.
    for (name, bytes) in [
        ("c.OBJ", obj_bytes(&off)),
        ("c.off", CUBE_OFF.as_bytes().to_vec()),
        ("c.ply", cube_ply_binary()),
    ] {
        let path = tmp(name);
        std::fs::write(&path, bytes).unwrap();
        assert_eq!(Mesh::load(&path).unwrap(), off, "{name}");
    }
    err_naming(Mesh::load(tmp("c.stl")), "c.stl");
}

fn obj_bytes(m: &Mesh) -> Vec<u8> {
    let mut s = String::new();
    m.positions
        .iter()
        .for_each(|p| s += &format!("v {} {} {}\n", p[0], p[1], p[2]));
    m.triangles
        .iter()
        .for_each(|t| s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
    s.into_bytes()
}

#[test]
fn mesh_loaders_reject_malformed_files() {
    let msg = err_naming(
        Mesh::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n", "x.obj"),
        "x.obj",
    );
    assert!(msg.contains("x.obj line 4") && msg.contains("99"), "{msg}");
    for (i, text) in [
        "v 0 0\n",
        "v 0 0 nan\n",
        "v 0 0 0\nf 1 1\n",
        "v 0 0 0\nf 0 1 1\n",
        "f a b c\n",
        "v 1 2 3\nf -2 1 1\n",
    ]
    .iter()
    .enumerate()
    {
        err_naming(
            Mesh::parse_obj(text, &format!("bad{i}.obj")),
            &format!("bad{i}.obj"),
        );
    }

    let truncated = &CUBE_OFF[..CUBE_OFF.len() - 30];
    let off_cases = [
        truncated.to_string(),
        CUBE_OFF.replace("4 4 5 7 6", "4 4 5 7 8"),
        CUBE_OFF.replace("4 4 5 7 6", "5 4 5 7 6"),
        CUBE_OFF.replace("OFF", "PLY"),
        "OFF\n".into(),
        "OFF\n3 1\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n".into(),
        String::new(),
    ];
    for (i, text) in off_cases.iter().enumerate() {
        err_naming(
            Mesh::parse_off(text, &format!("bad{i}.off")),
            &format!("bad{i}.off"),
        );
    }
    let msg = err_naming(Mesh::parse_off("OFF\n8 60000000 0\n", "big.off"), "big.off");
    assert!(msg.contains("limit of 50000000"), "{msg}");

    let bin = cube_ply_binary();
    let ply_cases: Vec<Vec<u8>> = vec![
        bin[..bin.len() - 7].to_vec(),
        bin[..40].to_vec(),
        cube_ply_header("binary_little_endian")
            .replace("vertex_indices", "vertex_indices\nproperty float")
            .into_bytes(),
        cube_ply_header("ascii")
            .replace("ply\n", "plx\n")
            .into_bytes(),
        cube_ply_header("ascii")
            .replace("ascii", "utf8")
            .into_bytes(),
        format!("{}0 0 0 1\n", cube_ply_header("ascii")).into_bytes(),
        format!(
            "{}{}",
            cube_ply_header("ascii"),
            "0 0 0 0\n".repeat(8) + "3 0 1 8\n"
        )
        .into_bytes(),
        b"ply\nformat ascii 1.0\nelement vertex 99999999999\nproperty float x\nend_header\n"
            .to_vec(),
    ];
    for (i, bytes) in ply_cases.iter().enumerate() {
        let file = format!("bad{i}.ply");
        err_naming(Mesh::parse_ply_bytes(bytes, &file), &file);
    }
    let msg = err_naming(
        Mesh::parse_ply_bytes(&bin[..bin.len() - 7], "t.ply"),
        "t.ply",
    );
    assert!(
        msg.contains("byte"),
        "binary errors give the byte offset: {msg}"
    );
}

#[test]
fn parsers_never_panic_on_truncated_or_corrupted_input() {
    let binvox = Binvox::from_grid(pattern_grid([6, 6, 6])).to_bytes();
    let obj = obj_bytes(&Mesh::parse_off(CUBE_OFF, "c.off").unwrap());
    let inputs = [binvox, obj, CUBE_OFF.as_bytes().to_vec(), cube_ply_binary()];
    for (k, bytes) in inputs.iter().enumerate() {
        let parse = |b: &[u8]| match k {
            0 => Binvox::parse(b, "f").map(|_| ()),
            1 => Mesh::parse_obj(&String::from_utf8_lossy(b), "f").map(|_| ()),
            2 => Mesh::parse_off(&String::from_utf8_lossy(b), "f").map(|_| ()),
            _ => Mesh::parse_ply_bytes(b, "f").map(|_| ()),
        };
        for cut in 0..bytes.len() {
            let _ = parse(&bytes[..cut]);
        }
        for (i, flip) in (0..bytes.len()).step_by(3).zip([0xff, b'9', b'-', 0x00, b'\n'].iter().cycle()) {
            let mut b = bytes.clone();
            b[i] = *flip;
            let _ = parse(&b);
        }
    }
}

#[test]
fn vox_round_trip_axes_and_malformed_files() {
    use rendernet::voxel::vox;
    // Hand-built file: SIZE 2 x 3 x 4 (x, y, z-up), one voxel at (1, 0, 3) with palette index 2.
    let chunk = |id: &[u8], content: Vec<u8>| {
        [id.to_vec(), (content.len() as i32).to_le_bytes().to_vec(), 0i32.to_le_bytes().to_vec(), content].concat()
    };
    let size: Vec<u8> = [2i32, 3, 4].iter().flat_map(|v| v.to_le_bytes()).collect();
    let xyzi = [1i32.to_le_bytes().to_vec(), vec![1, 0, 3, 2]].concat();
    let mut rgba = vec![0u8; 1024];
    rgba[4..8].copy_from_slice(&[255, 51, 0, 255]);
    let file = |children: Vec<u8>| {
        [b"VOX ".to_vec(), 150i32.to_le_bytes().to_vec(), b"MAIN".to_vec(), 0i32.to_le_bytes().to_vec(),
         (children.len() as i32).to_le_bytes().to_vec(), children].concat()
    };
    let good = file([chunk(b"SIZE", size.clone()), chunk(b"XYZI", xyzi.clone()), chunk(b"RGBA", rgba.clone())].concat());
    let g = vox::parse(&good, "hand.vox").unwrap();
    assert_eq!(g.dims(), [2, 4, 3], "[D, H, W] = [SX, SZ, SY]");
    assert_eq!(g.occupied_count(), 1);
    assert_eq!(g.get(1, 3, 2), 1.0, "(x, y, z) -> [x, z, SY - 1 - y]");
    let k = g.index(1, 3, 2);
    let c = g.colour().unwrap();
    assert_eq!([c[k], c[g.len() + k], c[2 * g.len() + k]], [1.0, 0.2, 0.0]);
    // Write and read back: same grid, same bytes.
    let path = tmp("rt.vox");
    vox::write(&g, &path).unwrap();
    assert_eq!(vox::read(&path).unwrap(), g);
    let plain = pattern_grid([5, 7, 9]);
    assert_eq!(vox::parse(&vox::to_bytes(&plain).unwrap(), "p.vox").unwrap(), plain);
    assert!(vox::to_bytes(&pattern_grid([300, 2, 2])).is_err());

    let trunc = good[..good.len() - 10].to_vec();
    let bad_xyz = file([chunk(b"SIZE", size.clone()), chunk(b"XYZI", [1i32.to_le_bytes().to_vec(), vec![2, 0, 0, 1]].concat())].concat());
    let big_count = file([chunk(b"SIZE", size.clone()), chunk(b"XYZI", [1000i32.to_le_bytes().to_vec(), vec![0, 0, 0, 1]].concat())].concat());
    let huge: Vec<u8> = [100000i32, 3, 4].iter().flat_map(|v| v.to_le_bytes()).collect();
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("empty", vec![]),
        ("magic", b"VOXX\x96\0\0\0".to_vec()),
        ("version", [b"VOX ".to_vec(), 7i32.to_le_bytes().to_vec()].concat()),
        ("truncated", trunc),
        ("nosize", file(chunk(b"XYZI", xyzi.clone()))),
        ("noxyzi", file(chunk(b"SIZE", size.clone()))),
        ("outside", bad_xyz),
        ("count", big_count),
        ("huge", file([chunk(b"SIZE", huge), chunk(b"XYZI", xyzi.clone())].concat())),
        ("palette", file([chunk(b"SIZE", size.clone()), chunk(b"XYZI", xyzi.clone()), chunk(b"RGBA", vec![0; 10])].concat())),
        ("negative", [b"VOX ".to_vec(), 150i32.to_le_bytes().to_vec(), b"MAIN".to_vec(), (-5i32).to_le_bytes().to_vec(), 0i32.to_le_bytes().to_vec()].concat()),
    ];
    for (name, bytes) in cases {
        let f = format!("{name}.vox");
        err_naming(vox::parse(&bytes, &f), &f);
    }
    err_naming(vox::read(tmp("missing.vox")), "missing.vox");
}

/// Vertex colours: OBJ `v x y z r g b` and PLY `red green blue` (uchar, scaled by 255) load
/// one colour per vertex (white for OBJ vertices given none once one has some); a colour
/// outside [0, 1] is an error naming the line.
#[test]
fn vertex_colours_load_from_obj_and_ply() {
    let obj = Mesh::parse_obj("v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0.5 1\nf 1 2 3\n", "c.obj").unwrap();
    assert_eq!(obj.colours, vec![[1.0, 0.0, 0.0], [1.0, 1.0, 1.0], [0.0, 0.5, 1.0]]);
    assert!(Mesh::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "g.obj").unwrap().colours.is_empty());
    let err = Mesh::parse_obj("v 0 0 0\nv 1 0 0 255 0 0\n", "bad.obj").unwrap_err().to_string();
    assert!(err.contains("bad.obj") && err.contains("line 2") && err.contains("[0, 1]"), "{err}");
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
               property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n\
               property list uchar int vertex_indices\nend_header\n0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 51\n3 0 1 2\n";
    let m = Mesh::parse_ply_bytes(ply.as_bytes(), "c.ply").unwrap();
    assert_eq!(m.colours, vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.2]]);
}
