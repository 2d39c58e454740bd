//! Procedural presets: named worlds generated chunk by chunk (`naadf generate --preset`).
//!
//! - `terrain`: hills, mountains, a sea, caves, overhangs, trees and buildings
//!   (default 1024×512×2048);
//! - `test`: a small world that holds empty, full and mixed chunks and blocks, for tests
//!   (default 64×64×64);
//! - `tiled:<file.vox>`: a MagicaVoxel scene repeated in X and Z.
//!
//! Every preset is a [`ChunkSource`]: a pure function of the seed and the voxel position,
//! never a dense array, so worlds of any size build in bounded memory.
//!
//! ```
//! use naadf_world::{World, WorldSize, preset::Preset};
//! let source = Preset::parse("test")?.source(Some(WorldSize::new(64, 64, 64)?), 7)?;
//! let world = World::build(&*source, &|_| {})?;
//! assert_eq!(world.size(), WorldSize::new(64, 64, 64)?);
//! # Ok::<(), naadf_world::WorldError>(())
//! ```

mod field;
mod terrain;
mod test;

use crate::build::ChunkSource;
use crate::error::WorldError;
use crate::import::vox::{TiledVox, VoxScene};
use crate::size::WorldSize;
use std::path::PathBuf;

/// A named procedural world.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Preset {
    /// Rolling hills, mountains, a sea, caves, overhangs, trees and buildings.
    Terrain,
    /// A small world with every kind of chunk and block, for tests.
    Test,
    /// A MagicaVoxel `.vox` scene tiled in X and Z (once in Y).
    Tiled(PathBuf),
}

/// Tiled worlds are at least this wide and deep.
const TILED_MIN_XZ: u32 = 1024;

impl Preset {
    /// Parses `terrain`, `test` or `tiled:<file.vox>`.
    ///
    /// # Errors
    /// [`WorldError::Preset`], listing the valid names, for anything else.
    ///
    /// ```
    /// use naadf_world::preset::Preset;
    /// assert_eq!(Preset::parse("terrain").unwrap(), Preset::Terrain);
    /// assert!(Preset::parse("moon").is_err());
    /// ```
    pub fn parse(name: &str) -> Result<Preset, WorldError> {
        let name = name.trim();
        match name {
            "terrain" => return Ok(Preset::Terrain),
            "test" => return Ok(Preset::Test),
            _ => {}
        }
        if let Some(path) = name.strip_prefix("tiled:") {
            if path.is_empty() {
                return Err(WorldError::Preset(
                    "'tiled:' needs a file, as in tiled:<file.vox>".into(),
                ));
            }
            return Ok(Preset::Tiled(PathBuf::from(path)));
        }
        Err(WorldError::Preset(format!(
            "'{name}' (valid presets: {})",
            Self::names().join(", ")
        )))
    }

    /// The preset names, as shown in command-line help.
    pub fn names() -> &'static [&'static str] {
        &["terrain", "test", "tiled:<file.vox>"]
    }

    /// The size a preset generates when none is given: terrain 1024×512×2048, test
    /// 64×64×64; tiled: the model's extent rounded up to 64, and at least 1024 in X and
    /// Z (this reads the `.vox` file).
    ///
    /// # Errors
    /// The `.vox` file's read or import error (tiled only).
    pub fn default_size(&self) -> Result<WorldSize, WorldError> {
        match self {
            Preset::Terrain => WorldSize::new(1024, 512, 2048),
            Preset::Test => WorldSize::new(64, 64, 64),
            Preset::Tiled(path) => tiled_size(&VoxScene::open(path)?),
        }
    }

    /// The chunk source of this preset at `size` (`None`: [`Preset::default_size`]),
    /// deterministic in `seed`.
    ///
    /// # Errors
    /// The `.vox` file's read or import error (tiled only), or an invalid default size.
    pub fn source(&self, size: Option<WorldSize>, seed: u64) -> Result<Box<dyn ChunkSource>, WorldError> {
        Ok(match self {
            Preset::Terrain => {
                let size = size.map_or_else(|| self.default_size(), Ok)?;
                Box::new(terrain::Terrain::new(size, seed))
            }
            Preset::Test => {
                let size = size.map_or_else(|| self.default_size(), Ok)?;
                Box::new(test::TestWorld::new(size, seed))
            }
            Preset::Tiled(path) => {
                let scene = VoxScene::open(path)?;
                let size = size.map_or_else(|| tiled_size(&scene), Ok)?;
                Box::new(TiledVox::new(scene, size))
            }
        })
    }
}

/// The default size of a tiled world for `scene`.
fn tiled_size(scene: &VoxScene) -> Result<WorldSize, WorldError> {
    let [x, y, z] = scene.extent();
    WorldSize::round_up(x.max(TILED_MIN_XZ), y, z.max(TILED_MIN_XZ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::World;
    use crate::cell::{self, CHUNK_VOXELS, State};

    fn fill(src: &dyn ChunkSource, c: [u32; 3]) -> Box<[u16; CHUNK_VOXELS]> {
        let mut out = Box::new([0u16; CHUNK_VOXELS]);
        src.fill_chunk(c, &mut out);
        out
    }

    fn all_chunks(size: WorldSize) -> impl Iterator<Item = [u32; 3]> {
        (0..size.chunk_count()).map(move |i| size.chunk_coords(i))
    }

    /// Counts of empty, full and mixed chunks.
    fn kinds(world: &World) -> [usize; 3] {
        let mut k = [0; 3];
        for &c in world.chunks() {
            k[match cell::state(c) {
                State::Empty => 0,
                State::Full => 1,
                State::Mixed => 2,
            }] += 1;
        }
        k
    }

    fn size(x: u32, y: u32, z: u32) -> WorldSize {
        WorldSize::new(x, y, z).unwrap()
    }

    #[test]
    fn parse_names_and_default_sizes() {
        assert_eq!(Preset::parse("terrain").unwrap(), Preset::Terrain);
        assert_eq!(Preset::parse(" test ").unwrap(), Preset::Test);
        assert_eq!(
            Preset::parse("tiled:models/castle.vox").unwrap(),
            Preset::Tiled(PathBuf::from("models/castle.vox"))
        );
        assert!(matches!(Preset::parse("tiled:"), Err(WorldError::Preset(_))));
        let err = Preset::parse("moon").unwrap_err();
        assert!(matches!(err, WorldError::Preset(_)));
        let msg = err.to_string();
        for n in Preset::names() {
            assert!(msg.contains(n), "{msg}");
        }
        assert_eq!(Preset::names(), &["terrain", "test", "tiled:<file.vox>"][..]);
        assert_eq!(Preset::Terrain.default_size().unwrap(), size(1024, 512, 2048));
        assert_eq!(Preset::Test.default_size().unwrap(), size(64, 64, 64));
        assert!(
            Preset::Tiled(PathBuf::from("/nonexistent/x.vox"))
                .default_size()
                .is_err()
        );
        assert_eq!(Preset::Test.source(None, 1).unwrap().size(), size(64, 64, 64));
    }

    #[test]
    fn presets_are_deterministic_in_the_seed() {
        for (preset, s) in [(Preset::Terrain, size(128, 128, 128)), (Preset::Test, size(64, 64, 64))] {
            let a = preset.source(Some(s), 11).unwrap();
            let b = preset.source(Some(s), 11).unwrap();
            let c = preset.source(Some(s), 12).unwrap();
            let mut differs = false;
            for ch in all_chunks(s) {
                let fa = fill(&*a, ch);
                assert_eq!(fa, fill(&*b, ch), "{preset:?} chunk {ch:?}");
                differs |= fa != fill(&*c, ch);
            }
            assert!(differs, "{preset:?}: seeds 11 and 12 give the same world");
        }
    }

    /// Every hint agrees with the chunk's content, and every id is defined.
    fn check_source(src: &dyn ChunkSource) -> usize {
        let table = src.materials();
        let mut hinted = 0;
        for ch in all_chunks(src.size()) {
            let raw = fill(src, ch);
            if let Some(&m) = raw.iter().find(|&&m| m != 0 && !table.contains(m)) {
                panic!("chunk {ch:?}: undefined material {m}");
            }
            if let Some(m) = src.uniform_hint(ch) {
                hinted += 1;
                assert!(
                    raw.iter().all(|&v| v == m),
                    "chunk {ch:?}: hint {m} but the chunk is not uniform"
                );
            }
        }
        hinted
    }

    #[test]
    fn hints_agree_and_materials_are_defined() {
        for (s, seed) in [
            (size(128, 128, 128), 1),
            (size(192, 64, 128), 2),
            (size(256, 256, 128), 3),
            (size(128, 512, 128), 4),
        ] {
            let t = Preset::Terrain.source(Some(s), seed).unwrap();
            assert!(check_source(&*t) > 0, "terrain {s}: no hints");
            let t = Preset::Test.source(Some(s), seed).unwrap();
            assert!(check_source(&*t) > 0, "test {s}: no hints");
        }
    }

    #[test]
    fn terrain_has_every_chunk_kind_and_its_features() {
        for (s, seed) in [(size(128, 128, 128), 5), (size(256, 128, 256), 6)] {
            let src = Preset::Terrain.source(Some(s), seed).unwrap();
            let world = World::build(&*src, &|_| {}).unwrap();
            let [empty, full, mixed] = kinds(&world);
            assert!(empty > 0 && full > 0 && mixed > 0, "{s}: {empty} {full} {mixed}");
        }
        // A larger world shows every material family somewhere.
        let s = size(512, 256, 512);
        let src = Preset::Terrain.source(Some(s), 9).unwrap();
        let mut seen = [false; terrain::mat::COUNT as usize + 1];
        for ch in all_chunks(s) {
            if src.uniform_hint(ch).is_none() {
                for &m in fill(&*src, ch).iter() {
                    seen[usize::from(m)] = true;
                }
            }
        }
        use terrain::mat::*;
        for m in [GRASS, DIRT, STONE, SAND, WATER, WOOD, BRICK, GLASS, METAL, LAMP, COBBLE] {
            assert!(seen[usize::from(m)], "material {m} never generated");
        }
        assert!(seen[usize::from(LEAVES)] || seen[usize::from(PINE)]);
        assert!(seen[0], "no air");
    }

    #[test]
    fn test_preset_has_every_kind_at_any_size() {
        for (s, seed) in [(size(64, 64, 64), 0), (size(128, 64, 192), 1), (size(64, 256, 64), 2)] {
            let src = Preset::Test.source(Some(s), seed).unwrap();
            let world = World::build(&*src, &|_| {}).unwrap();
            let [empty, full, mixed] = kinds(&world);
            assert!(empty > 0 && full > 0 && mixed > 0, "{s}: {empty} {full} {mixed}");
            // The designated full chunk and a corner voxel.
            assert_eq!(world.material_at([20, 40, 20]), test::mat::METAL);
            let [x, y, z] = s.voxels();
            assert_eq!(world.material_at([x - 1, y - 1, z - 1]), test::mat::LAMP);
            assert_eq!(world.material_at([0, 0, 0]), test::mat::STONE);
            // Full and empty blocks inside mixed chunks too.
            let mut block_kinds = [0usize; 3];
            for &c in world.chunks() {
                if cell::state(c) == State::Mixed {
                    for &b in &world.blocks()[cell::pointer(c) as usize..][..64] {
                        block_kinds[cell::state(b) as usize] += 1;
                    }
                }
            }
            assert!(block_kinds.iter().all(|&n| n > 0), "{s}: {block_kinds:?}");
            assert_eq!(world.material_at([40, 30, 40]), 0, "hollow box is hollow");
        }
    }

    #[test]
    fn tiled_preset_reads_the_model() {
        use dot_vox::{DotVoxData, Model, Size, Voxel};
        let model = Model {
            size: Size { x: 8, y: 6, z: 70 },
            voxels: (0..70).map(|z| Voxel { x: 1, y: 2, z, i: 4 }).collect(),
        };
        let data = DotVoxData {
            version: 150,
            index_map: dot_vox::DEFAULT_INDEX_MAP.to_vec(),
            models: vec![model],
            palette: dot_vox::DEFAULT_PALETTE.to_vec(),
            materials: vec![],
            scenes: vec![],
            layers: vec![],
        };
        let path = std::env::temp_dir().join(format!("naadf-preset-{}.vox", std::process::id()));
        data.write_vox(&mut std::fs::File::create(&path).unwrap()).unwrap();
        let preset = Preset::parse(&format!("tiled:{}", path.display())).unwrap();
        assert_eq!(preset.default_size().unwrap(), size(1024, 128, 1024));
        let src = preset.source(Some(size(64, 128, 64)), 0).unwrap();
        assert_eq!(src.size(), size(64, 128, 64));
        let world = World::build(&*src, &|_| {}).unwrap();
        // The column at vox (1, 2) repeats every 8 voxels in X and 6 in Z, 70 high.
        assert_ne!(world.material_at([1 + 8 * 3, 69, 2 + 6 * 5]), 0);
        assert_eq!(world.material_at([1 + 8 * 3, 70, 2 + 6 * 5]), 0);
        assert_eq!(world.material_at([2, 10, 2]), 0);
        std::fs::remove_file(&path).unwrap();
    }
}
