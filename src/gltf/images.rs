//! glTF images, decoded on first use: from a buffer view (GLB), a base64
//! data URI or an external file; each decoded once however many textures
//! share it, its size counted against the memory budget before decoding.

use super::buffers::{data_uri, uri_path, Buffers};
use super::GltfError;
use gltf::json;
use specula_raster::maps::ColorMap;
use specula_raster::texture::{Encoding, Filter, Sampler, Wrap};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

pub(crate) struct Images<'a> {
    pub(super) root: &'a json::Root,
    pub(super) buffers: &'a Buffers,
    pub(super) dir: PathBuf,
    pub(super) read: &'a dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    /// Files read (external images), for the scene's inputs.
    pub(crate) inputs: Vec<PathBuf>,
    cache: HashMap<(usize, Encoding, usize), ColorMap>,
}

impl<'a> Images<'a> {
    pub(super) fn new(
        root: &'a json::Root,
        buffers: &'a Buffers,
        dir: PathBuf,
        read: &'a dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    ) -> Images<'a> {
        Images {
            root,
            buffers,
            dir,
            read,
            inputs: Vec::new(),
            cache: HashMap::new(),
        }
    }

    /// `images[i]` decoded as `encoding` (sRGB for colours: base colour,
    /// emission; linear for data: metallic-roughness, normal, occlusion;
    /// v = 0 at the bottom row, like every texture here, glTF's uvs being
    /// flipped to match where meshes are read) with `channels` of RGBA
    /// kept: 3, or 4 for a base colour
    /// texture whose alpha a masked or blended material reads (alpha
    /// linear; 1 where the image has none). Each (image, encoding,
    /// channels) is decoded once.
    pub(crate) fn map_channels(
        &mut self,
        i: usize,
        encoding: Encoding,
        channels: usize,
    ) -> Result<ColorMap, GltfError> {
        if let Some(m) = self.cache.get(&(i, encoding, channels)) {
            return Ok(m.clone());
        }
        let at = format!("images[{i}]");
        let img = self
            .root
            .images
            .get(i)
            .ok_or_else(|| GltfError::at(&at, "no such image"))?;
        let bytes: Vec<u8> = match (&img.uri, img.buffer_view) {
            (Some(uri), _) => match data_uri(uri) {
                Some(r) => r.map_err(|source| GltfError::DataUri {
                    at: format!("{at}.uri"),
                    source,
                })?,
                None => {
                    let p = self.dir.join(uri_path(uri));
                    let b = (self.read)(&p).map_err(|source| GltfError::Read {
                        at: format!("{at}.uri"),
                        path: p.clone(),
                        source,
                    })?;
                    self.inputs.push(p);
                    b
                }
            },
            (None, Some(v)) => self
                .buffers
                .view(self.root, v.value(), &format!("{at}.bufferView"))?
                .0
                .to_vec(),
            (None, None) => return Err(GltfError::at(&at, "neither uri nor bufferView")),
        };
        let dims = image::ImageReader::new(std::io::Cursor::new(&bytes))
            .with_guessed_format()
            .ok()
            .and_then(|r| r.into_dimensions().ok());
        if dims.is_none() {
            return Err(GltfError::at(&at, "not an image this build can decode"));
        }
        let sampler = Sampler::new(Wrap::Repeat, Filter::Trilinear);
        let map = crate::textures::decode_map_channels(&at, &bytes, encoding, sampler, channels)?;
        self.cache.insert((i, encoding, channels), map.clone());
        Ok(map)
    }
}
