//! The common output of every hidden-surface algorithm: a face id and an eye-space
//! depth per pixel. Also shading, false colour, PNG and NumPy output, and the seed's
//! depth merge of two partial frames.

use std::io::Write;
use std::path::Path;

use glam::DVec3;

use crate::geom::Plane;
use crate::scene::{Camera, Scene, Viewport};
use crate::{Error, Result};

/// The id of pixels that show no face.
pub const BACKGROUND: u32 = u32::MAX;

/// Face id and depth per pixel, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Face id per pixel, [`BACKGROUND`] where no face is seen.
    pub ids: Vec<u32>,
    /// Eye-space depth per pixel (distance along the view axis), `+inf` for background.
    pub depth: Vec<f32>,
}

/// Bytes a frame and its shaded image take per pixel (id, depth, RGB).
const BYTES_PER_PIXEL: u64 = 4 + 4 + 3;

impl Frame {
    /// A frame of background, or an error if it would not fit in memory.
    pub fn new(viewport: Viewport) -> Result<Self> {
        // Huge pages: a 1080p frame in 4 KiB pages costs thousands of page faults.
        let mut frame = Self::allocate(
            viewport,
            |n| crate::memory::vec_with_capacity(n).ok(),
            |n| crate::memory::vec_with_capacity(n).ok(),
        )?;
        let n = viewport.pixel_count();
        frame.ids.resize(n, BACKGROUND);
        frame.depth.resize(n, f32::INFINITY);
        Ok(frame)
    }

    /// A frame of zero bits (ids 0, depths 0.0), or an error if it would not fit in
    /// memory: for renderers whose buffers encode "nothing drawn" as zero. The memory
    /// comes zeroed from the system, in huge pages where it has them, and nothing is
    /// written here: each page is first touched where the renderer first writes it.
    pub(crate) fn zeroed(viewport: Viewport) -> Result<Self> {
        Self::allocate(
            viewport,
            crate::memory::zeroed_vec,
            crate::memory::zeroed_vec,
        )
    }

    /// Makes this frame `viewport`'s size for a renderer that writes every pixel of it
    /// (its pixels are then unspecified): its memory is reused when it holds enough
    /// pixels (nothing allocated, no page faulted in: the point of keeping a frame from
    /// one render to the next), else it is replaced by [`Frame::zeroed`] (the old
    /// memory freed first). An error as [`Frame::zeroed`]'s leaves the frame empty
    /// (0x0).
    pub(crate) fn reshape(&mut self, viewport: Viewport) -> Result<()> {
        let n = viewport.pixel_count();
        if self.ids.capacity() >= n && self.depth.capacity() >= n {
            viewport.validate()?;
            self.ids.resize(n, 0);
            self.depth.resize(n, 0.0);
            (self.width, self.height) = (viewport.width, viewport.height);
            return Ok(());
        }
        *self = Frame {
            width: 0,
            height: 0,
            ids: Vec::new(),
            depth: Vec::new(),
        };
        *self = Self::zeroed(viewport)?;
        Ok(())
    }

    /// The frame's two buffers from the allocators (given the pixel count), after
    /// checking that the frame fits in memory; an error naming the size otherwise.
    fn allocate(
        viewport: Viewport,
        ids: impl FnOnce(usize) -> Option<Vec<u32>>,
        depth: impl FnOnce(usize) -> Option<Vec<f32>>,
    ) -> Result<Self> {
        viewport.validate()?;
        let n = viewport.pixel_count();
        let refuse = |reason: String| Error::InvalidViewport {
            width: u64::from(viewport.width),
            height: u64::from(viewport.height),
            reason,
        };
        check_fits(viewport, available_memory()).map_err(refuse)?;
        let cannot = |what| refuse(format!("cannot allocate {} MiB for {what}", (n * 4) >> 20));
        let ids = ids(n).ok_or_else(|| cannot("ids"))?;
        let depth = depth(n).ok_or_else(|| cannot("depths"))?;
        Ok(Frame {
            width: viewport.width,
            height: viewport.height,
            ids,
            depth,
        })
    }

    /// The viewport of this frame.
    #[must_use]
    pub fn viewport(&self) -> Viewport {
        Viewport {
            width: self.width,
            height: self.height,
        }
    }

    /// Index of pixel `(x, y)`.
    #[inline]
    #[must_use]
    pub fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }

    /// The id at pixel `(x, y)`.
    #[must_use]
    pub fn id(&self, x: u32, y: u32) -> u32 {
        self.ids[self.index(x, y)]
    }

    /// Number of pixels showing a face.
    #[must_use]
    pub fn covered_pixels(&self) -> usize {
        self.ids.iter().filter(|&&i| i != BACKGROUND).count()
    }

    /// The seed's depth merge of two frames of the same scene's parts (seed 000,
    /// "Αλγόριθμος Z-buffer (5)"): per pixel the nearer wins, the lower id on a tie.
    pub fn merge_depth(&self, other: &Frame) -> Result<Frame> {
        if self.width != other.width || self.height != other.height {
            return Err(Error::option(
                "merge_depth",
                format!(
                    "frames differ in size: {}x{} and {}x{}",
                    self.width, self.height, other.width, other.height
                ),
            ));
        }
        let mut out = self.clone();
        for i in 0..out.ids.len() {
            let (za, zb) = (self.depth[i], other.depth[i]);
            if zb < za || (zb == za && other.ids[i] < self.ids[i]) {
                out.ids[i] = other.ids[i];
                out.depth[i] = zb;
            }
        }
        Ok(out)
    }

    /// Pixels whose ids differ, as `(x, y, self id, other id)`.
    #[must_use]
    pub fn differences(&self, other: &Frame) -> Vec<(u32, u32, u32, u32)> {
        assert_eq!(
            (self.width, self.height),
            (other.width, other.height),
            "frames of different sizes"
        );
        let w = self.width as usize;
        self.ids
            .iter()
            .zip(&other.ids)
            .enumerate()
            .filter(|(_, (a, b))| a != b)
            .map(|(i, (&a, &b))| ((i % w) as u32, (i / w) as u32, a, b))
            .collect()
    }

    /// Writes the ids as a NumPy `int32` array of shape `(height, width)`, background -1.
    pub fn write_ids_npy(&self, path: &Path) -> Result<()> {
        let mut data = Vec::with_capacity(self.ids.len() * 4);
        for &id in &self.ids {
            let v: i32 = if id == BACKGROUND {
                -1
            } else {
                i32::try_from(id).unwrap_or(i32::MAX)
            };
            data.extend_from_slice(&v.to_le_bytes());
        }
        write_npy(path, "<i4", self.height, self.width, &data)
    }

    /// Writes the depths as a NumPy `float32` array of shape `(height, width)`,
    /// background `+inf`.
    pub fn write_depth_npy(&self, path: &Path) -> Result<()> {
        let mut data = Vec::with_capacity(self.depth.len() * 4);
        for &d in &self.depth {
            data.extend_from_slice(&d.to_le_bytes());
        }
        write_npy(path, "<f4", self.height, self.width, &data)
    }

    /// A colour per face id (hashed hues), background black: to see which face is where.
    #[must_use]
    pub fn id_false_colour(&self) -> RgbImage {
        let mut img = RgbImage::new(self.width, self.height);
        for (k, &id) in self.ids.iter().enumerate() {
            img.pixels[k] = if id == BACKGROUND {
                [0, 0, 0]
            } else {
                id_colour(id)
            };
        }
        img
    }

    /// Flat shading: the face's colour (material or object) lit by a fixed light from
    /// over the viewer's left shoulder, Lambert with an ambient term; faces seen from
    /// behind are lit as if facing the viewer. Background is a soft grey gradient.
    #[must_use]
    pub fn shade(&self, scene: &Scene, camera: &Camera) -> RgbImage {
        let (right, up, forward) = camera.basis();
        let light = (-right * 0.45 + up * 0.7 - forward * 0.55).normalize();
        let mut cache: std::collections::HashMap<u32, [u8; 3]> = std::collections::HashMap::new();
        let mut img = RgbImage::new(self.width, self.height);
        for y in 0..self.height {
            let t = y as f32 / self.height.max(1) as f32;
            let bg = [
                (236.0 - 30.0 * t) as u8,
                (238.0 - 28.0 * t) as u8,
                (242.0 - 20.0 * t) as u8,
            ];
            for x in 0..self.width {
                let k = self.index(x, y);
                let id = self.ids[k];
                img.pixels[k] = if id == BACKGROUND {
                    bg
                } else {
                    *cache
                        .entry(id)
                        .or_insert_with(|| face_shade(scene, camera, id, light))
                };
            }
        }
        img
    }
}

fn face_shade(scene: &Scene, camera: &Camera, id: u32, light: DVec3) -> [u8; 3] {
    let Some((k, face)) = scene.locate_face(id) else {
        return [255, 0, 255];
    };
    let o = &scene.objects()[k];
    let color = o.face_color(face);
    let Some(p) = o.mesh.polygons_of_face(face).next() else {
        return [255, 0, 255];
    };
    let pts = o.world_polygon(p);
    let Some(plane) = Plane::newell(&pts) else {
        return to_srgb(color, 0.5);
    };
    let mut n = if o.mirrored {
        -plane.normal
    } else {
        plane.normal
    };
    let to_eye = match camera.projection {
        crate::scene::Projection::Perspective { .. } => camera.eye - pts[0],
        crate::scene::Projection::Orthographic { .. } => camera.eye - camera.target,
    };
    if n.dot(to_eye) < 0.0 {
        n = -n;
    }
    let lambert = n.dot(light).max(0.0);
    to_srgb(color, 0.28 + 0.72 * lambert)
}

fn to_srgb(c: [f32; 3], k: f64) -> [u8; 3] {
    c.map(|v| ((f64::from(v) * k).clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0 + 0.5) as u8)
}

/// A distinct colour for an id (golden-ratio hues).
#[must_use]
pub fn id_colour(id: u32) -> [u8; 3] {
    let h = (f64::from(id.wrapping_mul(2_654_435_761) >> 8) / f64::from(1u32 << 24)
        + f64::from(id) * 0.618_033_988_75)
        .fract();
    let (s, v) = (
        0.65 + 0.3 * ((id >> 3) & 1) as f64,
        0.75 + 0.25 * ((id >> 4) & 1) as f64,
    );
    let i = (h * 6.0).floor();
    let f = h * 6.0 - i;
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - f * s), v * (1.0 - (1.0 - f) * s));
    let (r, g, b) = match i as i32 % 6 {
        0 => (v, t, p),
        1 => (q, v, p),
        2 => (p, v, t),
        3 => (p, q, v),
        4 => (t, p, v),
        _ => (v, p, q),
    };
    [(r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8]
}

/// An 8-bit RGB image.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbImage {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Pixels, row-major, row 0 at the top.
    pub pixels: Vec<[u8; 3]>,
}

impl RgbImage {
    /// A black image.
    #[must_use]
    pub fn new(width: u32, height: u32) -> Self {
        RgbImage {
            width,
            height,
            pixels: vec![[0; 3]; width as usize * height as usize],
        }
    }

    /// Writes a PNG file.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        let file = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), self.width, self.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        // Past 16 million pixels, fdeflate: about six times faster (an 8192x8192 picture
        // of a cube: 2.7 s of writing at the default level, 0.4 s) for a file about four
        // times larger; smaller pictures keep the smaller files.
        if self.pixels.len() > 1 << 24 {
            enc.set_compression(png::Compression::Fast);
        }
        let to_io = |e: png::EncodingError| Error::io(path, std::io::Error::other(e));
        let mut w = enc.write_header().map_err(to_io)?;
        w.write_image_data(self.pixels.as_flattened())
            .map_err(to_io)?;
        w.finish().map_err(to_io)
    }
}

fn write_npy(path: &Path, descr: &str, rows: u32, cols: u32, data: &[u8]) -> Result<()> {
    let mut header =
        format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': ({rows}, {cols}), }}");
    // Magic (6) + version (2) + length (2) + header, padded with spaces to a multiple of
    // 64 and ended by a newline.
    let total = 10 + header.len() + 1;
    header.push_str(&" ".repeat(total.div_ceil(64) * 64 - total));
    header.push('\n');
    let io = |e| Error::io(path, e);
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
    f.write_all(b"\x93NUMPY\x01\x00").map_err(io)?;
    f.write_all(&(header.len() as u16).to_le_bytes())
        .map_err(io)?;
    f.write_all(header.as_bytes()).map_err(io)?;
    f.write_all(data).map_err(io)?;
    f.flush().map_err(io)
}

/// Refuses a frame (with its shaded image) larger than the available memory.
fn check_fits(viewport: Viewport, available: Option<u64>) -> std::result::Result<(), String> {
    check_fits_many(viewport, 1, available)
}

/// Refuses `count` frames, each with its shaded image, that together exceed `available`
/// bytes (no limit when it is unknown).
fn check_fits_many(
    viewport: Viewport,
    count: u64,
    available: Option<u64>,
) -> std::result::Result<(), String> {
    let needed = (viewport.pixel_count() as u64)
        .saturating_mul(BYTES_PER_PIXEL)
        .saturating_mul(count);
    let what = if count == 1 {
        "the frame needs".to_string()
    } else {
        format!("{count} frames need")
    };
    match available {
        Some(avail) if needed > avail => Err(format!(
            "{what} {} MiB and only {} MiB of memory are available",
            needed >> 20,
            avail >> 20
        )),
        _ => Ok(()),
    }
}

/// Refuses holding `count` frames of this size at once, each with its shaded image (as
/// one [`Frame`] is checked when it is made), when they would not fit in `available`
/// bytes of memory ([`available_memory`] for this machine; `None`: no limit known): for
/// callers that keep several frames, such as a comparison of algorithms. The error
/// names the image size.
pub fn check_frames_fit(viewport: Viewport, count: u64, available: Option<u64>) -> Result<()> {
    check_fits_many(viewport, count, available).map_err(|reason| Error::InvalidViewport {
        width: u64::from(viewport.width),
        height: u64::from(viewport.height),
        reason,
    })
}

/// The memory available to a new allocation: `MemAvailable` from `/proc/meminfo`,
/// where there is one.
#[must_use]
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(ids: &[u32], depth: &[f32]) -> Frame {
        Frame {
            width: ids.len() as u32,
            height: 1,
            ids: ids.to_vec(),
            depth: depth.to_vec(),
        }
    }

    #[test]
    fn merge_takes_the_nearer_and_the_lower_id_on_ties() {
        let a = frame(&[1, 2, BACKGROUND, 7], &[1.0, 5.0, f32::INFINITY, 2.0]);
        let b = frame(&[3, 4, 5, 6], &[2.0, 4.0, 9.0, 2.0]);
        let m = a.merge_depth(&b).unwrap();
        assert_eq!(m.ids, vec![1, 4, 5, 6]);
        assert_eq!(m.depth, vec![1.0, 4.0, 9.0, 2.0]);
        assert_eq!(b.merge_depth(&a).unwrap().ids, vec![1, 4, 5, 6]);
    }

    #[test]
    fn npy_header_is_aligned_and_readable() {
        let f = frame(&[0, BACKGROUND, 5], &[1.0, f32::INFINITY, 2.5]);
        let dir = std::env::temp_dir().join(format!("obscura-npy-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("ids.npy");
        f.write_ids_npy(&p).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
        let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        assert_eq!((10 + hlen) % 64, 0);
        let header = std::str::from_utf8(&bytes[10..10 + hlen]).unwrap();
        assert!(
            header.contains("'shape': (1, 3)") && header.contains("<i4") && header.ends_with('\n')
        );
        let body = &bytes[10 + hlen..];
        let vals: Vec<i32> = body
            .chunks(4)
            .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(vals, vec![0, -1, 5]);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn frames_larger_than_memory_are_refused() {
        let vp = Viewport::new(16384, 16384).unwrap();
        let e = check_fits(vp, Some(1 << 30)).unwrap_err();
        assert!(e.contains("2816 MiB") && e.contains("1024 MiB"), "{e}");
        assert!(check_fits(vp, Some(1 << 40)).is_ok());
        assert!(check_fits(vp, None).is_ok());
        let e = check_frames_fit(vp, 3, Some(8 << 30))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("16384x16384") && e.contains("3 frames need 8448 MiB"),
            "{e}"
        );
        assert!(check_frames_fit(vp, 2, Some(8 << 30)).is_ok());
    }
}
