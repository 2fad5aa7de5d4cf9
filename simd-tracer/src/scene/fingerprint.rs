//! [`Scene::fingerprint`]: a 64-bit digest of what a scene renders, so that
//! parts of a frame rendered by different processes (or machines) can be
//! checked to come from the same scene before they are merged.
//!
//! What it covers: the spectral range, every triangle's vertices, material,
//! texture coordinates and vertex normals (of the scene's own triangles
//! and of each instanced mesh, with every instance's placement), the camera, the materials, the
//! spectra (their 32 Fourier coefficients), the constant environment, and
//! the sizes of the textures, angular tables and environment map. Texels
//! are not read (a texture file replaced by another of the same size is
//! not noticed): hashing images would cost as much as loading them again.
//!
//! The hash is FNV-1a over 32-bit words (Fowler, Noll and Vo; 64-bit
//! offset basis and prime from the reference at isthe.com/chongo/tech/comp/fnv),
//! chosen because it is stable across platforms and Rust releases (the
//! standard library's hasher promises neither) and quick: one multiply per
//! word, about 40 ms for a million triangles.

use super::Scene;
use crate::ids::MaterialId;
use glam::{Vec2, Vec3};

/// FNV-1a's 64-bit offset basis.
const FNV_OFFSET_BASIS: u64 = 0xcbf2_9ce4_8422_2325;
/// FNV-1a's 64-bit prime.
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// FNV-1a, fed 32-bit words.
struct Fnv(u64);

impl Fnv {
    fn word(&mut self, word: u32) {
        self.0 = (self.0 ^ u64::from(word)).wrapping_mul(FNV_PRIME);
    }

    fn floats(&mut self, values: impl IntoIterator<Item = f32>) {
        for value in values {
            self.word(value.to_bits());
        }
    }

    fn size(&mut self, size: usize) {
        let size = size as u64;
        self.word(size as u32);
        self.word((size >> 32) as u32);
    }

    fn text(&mut self, text: &str) {
        self.size(text.len());
        for chunk in text.as_bytes().chunks(4) {
            let mut word = [0u8; 4];
            word[..chunk.len()].copy_from_slice(chunk);
            self.word(u32::from_le_bytes(word));
        }
    }
}

impl Scene {
    /// A digest of what the scene renders (module docs): equal for scenes
    /// built from the same input by the same `fspec`, and different, with
    /// the probability of a 64-bit hash collision, for scenes that differ
    /// in geometry, camera, materials or spectra.
    pub fn fingerprint(&self) -> u64 {
        let mut hash = Fnv(FNV_OFFSET_BASIS);
        hash.text(&format!("{:?}", self.range()));
        hash.size(self.spectra().len());
        for spectrum in self.spectra() {
            hash.floats(spectrum.coefficients_f32().iter().copied());
        }
        hash.text(&format!("{:?}", self.materials()));
        hash.text(&format!("{:?}", self.camera()));
        hash.text(&format!("{:?}", self.environment()));
        let triangles = self.triangle_count();
        hash.size(triangles);
        // Read back by index where the tree holds the only copy, without a
        // vector of them all (`triangle_store`).
        let reader = self.triangles.reader(&self.bvh);
        for index in 0..triangles {
            let triangle = reader.get(index).unwrap_or([Vec3::NAN; 3]);
            hash.floats(triangle.iter().flat_map(|v| v.to_array()));
            let material = self.material_of(index).unwrap_or(MaterialId::NONE);
            hash.word(material.index() as u32);
        }
        // Every triangle's coordinates once any has some (zeros for those
        // without), as when they were stored for every triangle: digests
        // of earlier partial files stay valid.
        if self.has_uvs() {
            for index in 0..triangles {
                let uv = self.uvs(index).copied().unwrap_or([Vec2::ZERO; 3]);
                hash.floats(uv.iter().flat_map(|v| v.to_array()));
            }
        }
        for index in 0..triangles {
            if let Some(normals) = self.vertex_normals(index) {
                hash.floats(normals.iter().flat_map(|v| v.to_array()));
            }
        }
        hash.size(self.angular().len());
        for texture in self.textures() {
            hash.size(texture.memory_bytes());
        }
        hash.size(self.environment_map().map_or(0, |map| map.memory_bytes()));
        // Instances (absent from scenes without them, whose digest is thus
        // unchanged): each mesh's data, each instance's mesh, placement and
        // material.
        if let Some(instances) = self.instances() {
            hash.size(instances.meshes().len());
            for mesh in instances.meshes() {
                hash.size(mesh.triangles().len());
                for word in mesh.words() {
                    hash.word(word);
                }
            }
            hash.size(instances.len());
            for (index, mesh) in (0u32..).zip(instances.instance_meshes()) {
                hash.word(mesh);
                hash.text(&format!("{:?}", instances.placement(index)));
            }
        }
        hash.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin::{SceneOptions, builtin_scene};
    use spectral_core::SpectralRange;

    fn fingerprint(name: &str, range: SpectralRange) -> u64 {
        match builtin_scene(name, range, &SceneOptions::default()).map(|b| b.build()) {
            Ok(Ok(scene)) => scene.fingerprint(),
            _ => panic!("built-in scene {name}"),
        }
    }

    #[test]
    fn same_scene_same_fingerprint_other_scenes_differ() {
        let visible = SpectralRange::VISIBLE;
        let names = ["cornell", "lamps", "laser", "materials", "colorchecker"];
        let prints: Vec<u64> = names.iter().map(|n| fingerprint(n, visible)).collect();
        for (i, name) in names.iter().enumerate() {
            assert_eq!(prints[i], fingerprint(name, visible), "{name}");
            for j in 0..i {
                assert_ne!(prints[i], prints[j], "{name} vs {}", names[j]);
            }
        }
        // The same geometry over another range is another scene.
        let Ok(narrow) = SpectralRange::new(400.0, 700.0) else {
            panic!("range")
        };
        assert_ne!(prints[0], fingerprint("cornell", narrow));
    }

    #[test]
    fn fnv_matches_the_reference_value() {
        // The digest of nothing is the offset basis.
        let empty = Fnv(FNV_OFFSET_BASIS);
        assert_eq!(empty.0, 0xcbf2_9ce4_8422_2325);
        let mut one = Fnv(FNV_OFFSET_BASIS);
        one.word(u32::from(b'a'));
        // A word whose upper bytes are zero is one byte: the published
        // FNV-1a 64 test vector of "a" is 0xaf63dc4c8601ec8c.
        assert_eq!(one.0, 0xaf63_dc4c_8601_ec8c);
    }
}
