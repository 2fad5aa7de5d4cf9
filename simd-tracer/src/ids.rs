//! Indices into a scene's tables and the sentinels that mean "none".
//!
//! A leaf module: every stage (scene, tree, shading, transport) names
//! spectra, materials and triangles by these indices, so they live below
//! all of them and no stage imports another just for an index type. Each
//! table has its own index type, so a material id cannot index the spectra
//! by mistake; each is a `u32` underneath (`#[repr(transparent)]`), the
//! word that packed shading records and 8-wide gathers hold.

macro_rules! id_type {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        #[repr(transparent)]
        pub struct $name(pub u32);

        impl $name {
            /// "None": the sentinel of id fields without a value
            /// (`u32::MAX`, never a valid index).
            pub const NONE: Self = Self(NO_ID);

            /// The index into its table.
            #[inline(always)]
            pub const fn index(self) -> usize {
                self.0 as usize
            }

            /// Whether this is [`Self::NONE`].
            #[inline(always)]
            pub const fn is_none(self) -> bool {
                self.0 == NO_ID
            }

            /// The raw words of an array of ids (for 8-wide compares and
            /// gathers).
            #[inline(always)]
            pub fn words<const L: usize>(ids: [Self; L]) -> [u32; L] {
                ids.map(|id| id.0)
            }

            /// Ids from raw words.
            #[inline(always)]
            pub fn from_words<const L: usize>(words: [u32; L]) -> [Self; L] {
                words.map(Self)
            }
        }

        impl From<$name> for u32 {
            fn from(id: $name) -> u32 {
                id.0
            }
        }

        impl core::fmt::Display for $name {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                write!(f, "{}", self.0)
            }
        }
    };
}

id_type!(
    /// Index of a spectrum in the scene's spectra ([`crate::scene::Scene::spectra`]).
    SpectrumId
);
id_type!(
    /// Index of a material in the scene's materials ([`crate::scene::Scene::materials`]).
    MaterialId
);
id_type!(
    /// Index of an angular spectrum in [`crate::scene::Scene::angular`].
    AngularId
);
id_type!(
    /// Index of a texture in [`crate::scene::Scene::textures`].
    TextureId
);
id_type!(
    /// Index of a fluorophore in [`crate::scene::Scene::fluorophores`].
    FluorophoreId
);

/// The raw word of every id's "none" ([`SpectrumId::NONE`] and its
/// siblings), as packed records and 8-wide gathers hold it.
pub const NO_ID: u32 = u32::MAX;

/// Triangle index of packet lanes that hit nothing.
pub const NO_TRIANGLE: u32 = u32::MAX;

/// The instance of a hit on the scene's own (flattened) triangles: no
/// instance ([`crate::packet::PacketHit::instance`]).
pub const NO_INSTANCE: u32 = u32::MAX;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_their_words_and_none_is_the_sentinel() {
        assert_eq!(size_of::<SpectrumId>(), size_of::<u32>());
        assert!(SpectrumId::NONE.is_none() && !SpectrumId(0).is_none());
        assert_eq!(MaterialId(7).index(), 7);
        assert_eq!(u32::from(TextureId(3)), 3);
        let ids = [SpectrumId(1), SpectrumId::NONE, SpectrumId(0)];
        assert_eq!(SpectrumId::words(ids), [1, NO_ID, 0]);
        assert_eq!(SpectrumId::from_words(SpectrumId::words(ids)), ids);
        assert_eq!(AngularId(4).to_string(), "4");
    }
}
