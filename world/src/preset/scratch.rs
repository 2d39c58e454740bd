//! THROWAWAY: visual checks. Delete before finishing.
#![allow(missing_docs, dead_code)]
use super::*;
use crate::World;
use std::io::Write;

fn crc32(data: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in data {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
        }
    }
    !c
}

pub fn write_png(path: &str, w: usize, h: usize, rgb: &[u8]) {
    let mut raw = Vec::new();
    for y in 0..h {
        raw.push(0u8);
        raw.extend_from_slice(&rgb[y * w * 3..(y + 1) * w * 3]);
    }
    let mut z = vec![0x78, 0x01];
    let chunks: Vec<&[u8]> = raw.chunks(65535).collect();
    for (i, c) in chunks.iter().enumerate() {
        z.push(u8::from(i + 1 == chunks.len()));
        z.extend_from_slice(&(c.len() as u16).to_le_bytes());
        z.extend_from_slice(&(!(c.len() as u16)).to_le_bytes());
        z.extend_from_slice(c);
    }
    let (mut a, mut b) = (1u32, 0u32);
    for &x in &raw {
        a = (a + u32::from(x)) % 65521;
        b = (b + a) % 65521;
    }
    z.extend_from_slice(&((b << 16) | a).to_be_bytes());
    let mut f = std::fs::File::create(path).unwrap();
    f.write_all(b"\x89PNG\r\n\x1a\n").unwrap();
    let mut chunk = |t: &[u8], d: &[u8]| {
        f.write_all(&(d.len() as u32).to_be_bytes()).unwrap();
        let mut td = t.to_vec();
        td.extend_from_slice(d);
        f.write_all(&td).unwrap();
        f.write_all(&crc32(&td).to_be_bytes()).unwrap();
    };
    let mut ih = Vec::new();
    ih.extend_from_slice(&(w as u32).to_be_bytes());
    ih.extend_from_slice(&(h as u32).to_be_bytes());
    ih.extend_from_slice(&[8, 2, 0, 0, 0]);
    chunk(b"IHDR", &ih);
    chunk(b"IDAT", &z);
    chunk(b"IEND", &[]);
}

fn color(world: &World, m: u16) -> [f32; 3] {
    let mm = world.materials().get(m).unwrap();
    let a = mm.albedo;
    if mm.kind == crate::MaterialKind::Emissive { return [1.0, 0.0, 1.0]; }
    a
}

fn srgb(v: f32) -> u8 { (v.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0) as u8 }

pub fn views(world: &World, name: &str) {
    let [sx, sy, sz] = world.size().voxels();
    // top-down
    let (w, h) = (sx as usize, sz as usize);
    let mut img = vec![0u8; w * h * 3];
    let mut hm = vec![0i32; w * h];
    let mut mm = vec![0u16; w * h];
    for z in 0..sz {
        for x in 0..sx {
            let mut y = sy as i32 - 1;
            while y >= 0 && world.material_at([x, y as u32, z]) == 0 { y -= 1; }
            hm[x as usize + w * z as usize] = y;
            mm[x as usize + w * z as usize] = if y >= 0 { world.material_at([x, y as u32, z]) } else { 0 };
        }
    }
    for z in 0..h {
        for x in 0..w {
            let i = x + w * z;
            let c = if mm[i] == 0 { [0.0; 3] } else { color(world, mm[i]) };
            let hx = hm[(x + 1).min(w - 1) + w * z] - hm[x.saturating_sub(1) + w * z];
            let hz = hm[x + w * (z + 1).min(h - 1)] - hm[x + w * z.saturating_sub(1)];
            let shade = (1.0 + 0.15 * (hx as f32 + hz as f32)).clamp(0.3, 1.6) * (0.5 + 0.5 * hm[i] as f32 / sy as f32);
            for k in 0..3 { img[3 * i + k] = srgb(c[k] * shade * 1.5); }
        }
    }
    write_png(&format!("/tmp/{name}_top.png"), w, h, &img);
    // slices along x at a few z
    for (n, zc) in [sz / 3, sz / 2, 2 * sz / 3].into_iter().enumerate() {
        let (w, h) = (sx as usize, sy as usize);
        let mut img = vec![0u8; w * h * 3];
        for y in 0..sy {
            for x in 0..sx {
                let m = world.material_at([x, y, zc]);
                let c = if m == 0 { [0.6, 0.8, 1.0] } else { color(world, m) };
                let i = x as usize + w * (sy - 1 - y) as usize;
                for k in 0..3 { img[3 * i + k] = srgb(c[k] * 1.3); }
            }
        }
        write_png(&format!("/tmp/{name}_slice{n}.png"), w, h, &img);
    }
}

#[test]
#[ignore]
fn scratch_views() {
    let sizes: Vec<(u32, u32, u32)> = std::env::var("SIZES").unwrap_or("512,256,512".into())
        .split(';').map(|s| { let v: Vec<u32> = s.split(',').map(|t| t.parse().unwrap()).collect(); (v[0], v[1], v[2]) }).collect();
    let seed: u64 = std::env::var("SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(1);
    for (x, y, z) in sizes {
        let s = WorldSize::new(x, y, z).unwrap();
        let src = Preset::Terrain.source(Some(s), seed).unwrap();
        let t = std::time::Instant::now();
        let world = World::build(&*src, &|_| {}).unwrap();
        let dt = t.elapsed();
        let st = crate::stats::WorldStats::of(&world);
        eprintln!("{s}: build {dt:?} stats {st:?}");
        if std::env::var("NOVIEW").is_err() { views(&world, &format!("t{x}x{y}x{z}")); }
    }
}

#[test]
#[ignore]
fn scratch_overhangs() {
    let s = WorldSize::new(512, 256, 512).unwrap();
    let seed: u64 = std::env::var("SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(1);
    let src = Preset::Terrain.source(Some(s), seed).unwrap();
    let world = World::build(&*src, &|_| {}).unwrap();
    let mut count = 0;
    let mut best = (0, 0u32);
    for z in 0..512 {
        let mut row = 0;
        for x in 0..512 {
            for y in 90..255 {
                let m = world.material_at([x, y, z]);
                if (m == 1 || m == 3) && world.material_at([x, y - 1, z]) == 0 {
                    // air below, and is there ground further below within 40?
                    count += 1; row += 1;
                }
            }
        }
        if row > best.0 { best = (row, z); }
    }
    eprintln!("overhang voxels {count}, best row z={} ({})", best.1, best.0);
    for zc in [270u32, 276, 282] {
    let (w, h) = (512usize, 256usize);
    let mut img = vec![0u8; w * h * 3];
    for y in 0..256u32 {
        for x in 0..512u32 {
            let m = world.material_at([x, y, zc]);
            let c = if m == 0 { [0.6, 0.8, 1.0] } else { color(&world, m) };
            let i = x as usize + w * (255 - y) as usize;
            for k in 0..3 { img[3 * i + k] = srgb(c[k] * 1.3); }
        }
    }
    write_png(&format!("/tmp/overhang{zc}.png"), w, h, &img);
    }
}
