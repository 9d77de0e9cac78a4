//! Writing (and reading back) images: PNG as 8-bit sRGB per spec §8, EXR as linear
//! 32-bit float RGB. Files are written to a temporary sibling and renamed into place,
//! so a failure never leaves a partial file.

use crate::film::Image;
use crate::image_metadata::ImageMetadata;
use crate::render::PixelRect;
use crate::shard::Part;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum ImageIoError {
    #[error("{path}: unsupported image extension (use .png or .exr)")]
    UnknownFormat { path: String },
    #[error("{path}: cannot write")]
    Write {
        path: String,
        source: std::io::Error,
    },
    #[error("{path}: is a directory, not an image file")]
    IsDirectory { path: String },
    #[error("{path}: is also an input of this command (the scene, a map or a part); choose another output file")]
    SameAsInput { path: String },
    #[error("{path}: cannot encode: {msg}")]
    Encode { path: String, msg: String },
    #[error("{path}: cannot read image: {msg}")]
    Read { path: String, msg: String },
}

/// Output format chosen by the file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    Png,
    Exr,
}

impl OutputFormat {
    pub fn from_path(path: &Path) -> Result<Self, ImageIoError> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("png") => Ok(OutputFormat::Png),
            Some("exr") => Ok(OutputFormat::Exr),
            _ => Err(ImageIoError::UnknownFormat {
                path: path.display().to_string(),
            }),
        }
    }
}

/// Whether `a` and `b` name one existing file (through links and `..`), so that
/// writing one would overwrite the other.
pub fn is_same_file(a: &Path, b: &Path) -> bool {
    matches!((a.canonicalize(), b.canonicalize()), (Ok(a), Ok(b)) if a == b)
}

/// The sRGB transfer function of spec §8 applied to a clamped linear value, rounded.
pub fn srgb8(x: f32) -> u8 {
    let x = if x.is_finite() {
        x.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let v = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (v * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Writes `img` to `path` in the format its extension names.
pub fn write_image(img: &Image, path: &Path) -> Result<(), ImageIoError> {
    PendingImage::claim(path, &[])?.write(img)
}

/// An output file checked and claimed before any work: the extension is known, the
/// path is not one of the inputs, and its temporary sibling already exists (so the
/// directory exists and is writable). [`PendingImage::write`] fills the temporary and
/// renames it into place; dropping an unwritten `PendingImage` removes the temporary,
/// so no partial file is ever left at `path`.
#[derive(Debug)]
pub struct PendingImage {
    path: PathBuf,
    tmp: PathBuf,
    format: OutputFormat,
    file: Option<File>,
}

impl PendingImage {
    /// Checks `path` as an output for a job reading `inputs`, and creates its temporary.
    pub fn claim(path: &Path, inputs: &[&Path]) -> Result<Self, ImageIoError> {
        let format = OutputFormat::from_path(path)?;
        let display = path.display().to_string();
        if path.is_dir() {
            return Err(ImageIoError::IsDirectory { path: display });
        }
        if inputs.iter().any(|i| is_same_file(path, i)) {
            return Err(ImageIoError::SameAsInput { path: display });
        }
        let tmp = temp_sibling(path);
        let file = create_temp(&tmp, path)?;
        temporaries::register(&tmp);
        Ok(PendingImage {
            path: path.to_path_buf(),
            tmp,
            format,
            file: Some(file),
        })
    }

    /// The format the path's extension names.
    pub fn format(&self) -> OutputFormat {
        self.format
    }

    /// The final path the image will be renamed to.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Encodes `img` into the temporary, syncs it and renames it into place.
    pub fn write(self, img: &Image) -> Result<(), ImageIoError> {
        self.write_with_metadata(img, &ImageMetadata::default())
    }

    /// As [`PendingImage::write`], recording `meta` in the file (EXR attributes, PNG text).
    pub fn write_with_metadata(
        mut self,
        img: &Image,
        meta: &ImageMetadata,
    ) -> Result<(), ImageIoError> {
        self.commit(ImageData::Whole(img), meta)
    }

    /// Writes a part of a sharded render (an EXR, see [`write_part_exr`]).
    pub fn write_part(mut self, part: &Part) -> Result<(), ImageIoError> {
        if self.format != OutputFormat::Exr {
            return Err(ImageIoError::Encode {
                path: self.path.display().to_string(),
                msg: "a part of a sharded render (--shard, --spp-offset) must be an .exr".into(),
            });
        }
        self.commit(ImageData::Part(part), &part.meta)
    }

    /// Writes `img` to the path now (a checkpoint of a long render) and claims a new
    /// temporary for the next write, so the path always holds a whole image.
    pub fn checkpoint(&mut self, img: &Image, meta: &ImageMetadata) -> Result<(), ImageIoError> {
        self.commit(ImageData::Whole(img), meta)?;
        self.file = Some(create_temp(&self.tmp, &self.path)?);
        Ok(())
    }

    /// Encodes into the temporary, syncs it and renames it into place.
    fn commit(&mut self, data: ImageData, meta: &ImageMetadata) -> Result<(), ImageIoError> {
        let display = self.path.display().to_string();
        let file = self
            .file
            .take()
            .expect("a pending image is claimed before each write");
        let written = write_to_file(data, meta, file, self.format, &display).and_then(|()| {
            std::fs::rename(&self.tmp, &self.path).map_err(|source| ImageIoError::Write {
                path: display,
                source,
            })
        });
        if written.is_err() {
            let _ = std::fs::remove_file(&self.tmp);
        }
        written
    }
}

/// Creates the temporary `tmp` of output `path`, failing if it exists.
fn create_temp(tmp: &Path, path: &Path) -> Result<File, ImageIoError> {
    OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(tmp)
        .map_err(|source| ImageIoError::Write {
            path: path.display().to_string(),
            source,
        })
}

impl Drop for PendingImage {
    /// Removes the temporary if it is still claimed (not renamed into place).
    fn drop(&mut self) {
        if self.file.is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Removes the temporaries of every output claimed and not yet written, for an exit
/// that runs no destructors (a second Ctrl-C). Async-signal-safe: it only reads
/// atomics and calls `unlink`, so a signal handler may call it.
pub fn remove_claimed_temporaries() {
    temporaries::remove_all();
}

/// The paths of claimed temporaries, readable from a signal handler: fixed slots of
/// pointers to NUL-terminated paths. A path's allocation is never freed (a few bytes
/// per output per process), so a handler never reads freed memory; a temporary that
/// was already renamed or removed makes `unlink` fail harmlessly.
mod temporaries {
    use std::ffi::{c_char, CString};
    use std::os::unix::ffi::OsStrExt;
    use std::path::Path;
    use std::sync::atomic::{AtomicPtr, Ordering};

    const SLOTS: usize = 16;
    static CLAIMED: [AtomicPtr<c_char>; SLOTS] =
        [const { AtomicPtr::new(std::ptr::null_mut()) }; SLOTS];

    pub(super) fn register(tmp: &Path) {
        let Ok(c) = CString::new(tmp.as_os_str().as_bytes()) else {
            return;
        };
        let raw = c.into_raw();
        // Slots are reused round robin once full: only the latest outputs matter.
        static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let slot = NEXT.fetch_add(1, Ordering::Relaxed) % SLOTS;
        CLAIMED[slot].store(raw, Ordering::SeqCst);
    }

    pub(super) fn remove_all() {
        for slot in &CLAIMED {
            let p = slot.load(Ordering::SeqCst);
            if !p.is_null() {
                // SAFETY: `p` is a NUL-terminated string that is never freed.
                unsafe { libc::unlink(p) };
            }
        }
    }
}

/// Writes `bytes` to `path` through a temporary sibling renamed into place, so a
/// failure (a full disk, an interrupt) never leaves a partial file: every file ember
/// writes, not only images, goes through here or [`PendingImage`].
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temp_sibling(path);
    temporaries::register(&tmp);
    let written = File::create(&tmp)
        .and_then(|mut f| f.write_all(bytes).and_then(|()| f.sync_all()))
        .and_then(|()| std::fs::rename(&tmp, path));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

fn temp_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// What a file holds: a whole image, or a part of a sharded render.
#[derive(Clone, Copy)]
enum ImageData<'a> {
    Whole(&'a Image),
    Part(&'a Part),
}

fn write_to_file(
    data: ImageData,
    meta: &ImageMetadata,
    file: File,
    format: OutputFormat,
    display: &str,
) -> Result<(), ImageIoError> {
    let werr = |source| ImageIoError::Write {
        path: display.to_string(),
        source,
    };
    let enc = |msg: String| ImageIoError::Encode {
        path: display.to_string(),
        msg,
    };
    let mut out = BufWriter::new(file);
    let exr_err = |e| match e {
        exr::error::Error::Io(io) => werr(io),
        e => enc(e.to_string()),
    };
    match (format, data) {
        (OutputFormat::Png, ImageData::Whole(img)) => {
            write_png(img, meta, &mut out).map_err(|e| match e {
                png::EncodingError::IoError(io) => werr(io),
                e => enc(e.to_string()),
            })?
        }
        (OutputFormat::Exr, ImageData::Whole(img)) => {
            write_exr(img, meta, &mut out).map_err(exr_err)?
        }
        (OutputFormat::Exr, ImageData::Part(p)) => write_part_exr(p, &mut out).map_err(exr_err)?,
        (OutputFormat::Png, ImageData::Part(_)) => {
            return Err(enc("a part must be an .exr".into()))
        }
    }
    out.flush().map_err(werr)?;
    let file = out.into_inner().map_err(|e| werr(e.into_error()))?;
    file.sync_all().map_err(werr)
}

/// 8-bit sRGB PNG with one iTXt chunk per metadata entry (UTF-8 keys and values).
fn write_png(
    img: &Image,
    meta: &ImageMetadata,
    out: &mut impl Write,
) -> Result<(), png::EncodingError> {
    let mut encoder = png::Encoder::new(out, img.width, img.height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    for (k, v) in &meta.entries {
        encoder.add_itxt_chunk(k.clone(), v.clone())?;
    }
    let mut writer = encoder.write_header()?;
    let buf: Vec<u8> = img
        .pixels
        .iter()
        .flat_map(|p| [srgb8(p.x), srgb8(p.y), srgb8(p.z)])
        .collect();
    writer.write_image_data(&buf)?;
    writer.finish()
}

fn exr_attributes(meta: &ImageMetadata) -> exr::prelude::LayerAttributes {
    use exr::prelude::*;
    let mut attributes = LayerAttributes::default();
    for (k, v) in &meta.entries {
        attributes.other.insert(
            Text::from_slice_unchecked(k.as_bytes()),
            AttributeValue::Text(Text::from_slice_unchecked(v.as_bytes())),
        );
    }
    attributes
}

/// A part of a sharded render: the display window is the whole image, the data window
/// the part's pixels; linear f32 `R`, `G`, `B` and a u32 `samples` channel (each
/// pixel's sample count, the merge weights); the header as string attributes.
fn write_part_exr(part: &Part, out: &mut (impl Write + std::io::Seek)) -> exr::error::Result<()> {
    use exr::prelude::*;
    let px = &part.image.pixels;
    let channel = |name: &str, f: fn(&crate::Color) -> f32| {
        AnyChannel::new(name, FlatSamples::F32(px.iter().map(f).collect()))
    };
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![
        channel("R", |c| c.x),
        channel("G", |c| c.y),
        channel("B", |c| c.z),
        AnyChannel::new("samples", FlatSamples::U32(part.samples.clone())),
    ]));
    let r = part.rect;
    let mut attributes = exr_attributes(&part.meta);
    attributes.layer_position = Vec2(r.x0 as i32, r.y0 as i32);
    let layer = Layer::new(
        (r.width() as usize, r.height() as usize),
        attributes,
        Encoding::SMALL_LOSSLESS,
        channels,
    );
    let frame = Vec2(part.frame.0 as usize, part.frame.1 as usize);
    let image = exr::image::Image::new(
        ImageAttributes::new(IntegerBounds::from_dimensions(frame)),
        layer,
    );
    image.write().to_buffered(out)
}

/// Reads a part written by [`PendingImage::write_part`].
pub fn read_part(path: &Path) -> Result<Part, ImageIoError> {
    use exr::prelude::*;
    let name = path.display().to_string();
    let err = |msg: String| ImageIoError::Read {
        path: name.clone(),
        msg,
    };
    if OutputFormat::from_path(path)? != OutputFormat::Exr {
        return Err(err("a part of a sharded render is an .exr".into()));
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| err(e.to_string()))?;
    let layer = &image.layer_data;
    let channel = |n: &str| {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.eq(n))
            .map(|c| &c.sample_data)
            .ok_or_else(|| err(format!("no {n} channel: not a part of a sharded render (render it with --shard or --spp-offset)")))
    };
    let f32s = |n: &str| -> std::result::Result<Vec<f32>, ImageIoError> {
        Ok(channel(n)?.values_as_f32().collect())
    };
    let (r, g, b) = (f32s("R")?, f32s("G")?, f32s("B")?);
    let samples = match channel("samples")? {
        FlatSamples::U32(v) => v.clone(),
        _ => return Err(err("the samples channel is not u32".into())),
    };
    let pos = layer.attributes.layer_position;
    let window = image.attributes.display_window;
    if pos.x() < 0 || pos.y() < 0 || window.position != Vec2(0, 0) {
        return Err(err("its data window lies outside the image".into()));
    }
    let (w, h) = (layer.size.width() as u32, layer.size.height() as u32);
    let rect = PixelRect {
        x0: pos.x() as u32,
        y0: pos.y() as u32,
        x1: pos.x() as u32 + w,
        y1: pos.y() as u32 + h,
    };
    let pixels = (0..r.len())
        .map(|i| crate::Color::new(r[i], g[i], b[i]))
        .collect();
    let mut meta = ImageMetadata::default();
    for (k, v) in &layer.attributes.other {
        if let AttributeValue::Text(t) = v {
            meta.push(
                String::from_utf8_lossy(k.bytes()).into_owned(),
                String::from_utf8_lossy(t.bytes()).into_owned(),
            );
        }
    }
    meta.entries.sort();
    Ok(Part {
        name,
        meta,
        frame: (window.size.width() as u32, window.size.height() as u32),
        rect,
        image: crate::film::Image {
            width: w,
            height: h,
            pixels,
        },
        samples,
    })
}

/// Linear 32-bit float RGB EXR with one string attribute per metadata entry.
fn write_exr(
    img: &Image,
    meta: &ImageMetadata,
    out: &mut (impl Write + std::io::Seek),
) -> exr::error::Result<()> {
    use exr::prelude::*;
    let attributes = exr_attributes(meta);
    let width = img.width as usize;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = img.pixels[y * width + x];
        (p.x, p.y, p.z)
    });
    let layer = Layer::new(
        (width, img.height as usize),
        attributes,
        Encoding::SMALL_LOSSLESS,
        channels,
    );
    Image::from_layer(layer).write().to_buffered(out)
}

/// The metadata stored in a PNG's text chunks or an EXR's string attributes (EXR
/// headers keep no order, so its entries come back sorted by key).
pub fn read_metadata(path: &Path) -> Result<ImageMetadata, ImageIoError> {
    let err = |msg: String| ImageIoError::Read {
        path: path.display().to_string(),
        msg,
    };
    let file = std::io::BufReader::new(File::open(path).map_err(|e| err(e.to_string()))?);
    let mut meta = ImageMetadata::default();
    match OutputFormat::from_path(path)? {
        OutputFormat::Png => {
            let reader = png::Decoder::new(file)
                .read_info()
                .map_err(|e| err(e.to_string()))?;
            let info = reader.info();
            for t in &info.uncompressed_latin1_text {
                meta.push(t.keyword.clone(), &t.text);
            }
            for t in &info.utf8_text {
                let text = t.get_text().map_err(|e| err(e.to_string()))?;
                meta.push(t.keyword.clone(), text);
            }
        }
        OutputFormat::Exr => {
            let header = exr::meta::MetaData::read_from_buffered(file, false)
                .map_err(|e| err(e.to_string()))?;
            let mut entries: Vec<(String, String)> = header
                .headers
                .iter()
                .flat_map(|h| h.own_attributes.other.iter())
                .filter_map(|(k, v)| match v {
                    exr::meta::attribute::AttributeValue::Text(t) => Some((
                        String::from_utf8_lossy(k.bytes()).into_owned(),
                        String::from_utf8_lossy(t.bytes()).into_owned(),
                    )),
                    _ => None,
                })
                .collect();
            entries.sort();
            meta.entries = entries;
        }
    }
    Ok(meta)
}

/// Reads a linear float image (EXR) or a PNG (decoded back to linear).
pub fn read_image(path: &Path) -> Result<Image, ImageIoError> {
    let err = |msg: String| ImageIoError::Read {
        path: path.display().to_string(),
        msg,
    };
    let dynimg = image::open(path).map_err(|e| err(e.to_string()))?;
    let rgb = dynimg.to_rgb32f();
    let (w, h) = rgb.dimensions();
    let is_png = OutputFormat::from_path(path).ok() == Some(OutputFormat::Png);
    let pixels = rgb
        .pixels()
        .map(|p| {
            let c = crate::Color::new(p[0], p[1], p[2]);
            if is_png {
                c.to_array().map(srgb_to_linear).into()
            } else {
                c
            }
        })
        .collect();
    Ok(Image {
        width: w,
        height: h,
        pixels,
    })
}

fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_matches_spec_points() {
        assert_eq!(srgb8(0.0), 0);
        assert_eq!(srgb8(1.0), 255);
        assert_eq!(srgb8(2.0), 255);
        assert_eq!(srgb8(f32::NAN), 0);
        // 0.5 linear → 1.055·0.5^(1/2.4) − 0.055 = 0.7354 → 187.5 → 188
        assert_eq!(srgb8(0.5), 188);
        assert_eq!(srgb8(0.002), (0.002f32 * 12.92 * 255.0).round() as u8);
    }
}
