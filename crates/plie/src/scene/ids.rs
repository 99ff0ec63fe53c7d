//! Newtype indices, so a triangle index cannot be passed where a light index is meant.

use serde::{Deserialize, Serialize};

macro_rules! id_type {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
        pub struct $name(pub u32);

        impl $name {
            /// The index as `usize`.
            #[inline]
            pub fn idx(self) -> usize {
                self.0 as usize
            }
        }
    };
}

id_type!(
    /// Index of a triangle in [`crate::Scene::triangles`].
    TriId
);
id_type!(
    /// Index of a light in [`crate::Scene::lights`].
    LightId
);
id_type!(
    /// Index of a texture in [`crate::Scene::textures`].
    TextureId
);
id_type!(
    /// Index of a material in [`crate::Scene::materials`].
    MaterialId
);
