//! The buffers of a glTF file (the GLB chunk, data URIs, files beside it) and the
//! accessors read from them, every read bounds-checked.

use super::{MAX_GLTF_BYTES, fail};
use crate::error::SceneError;
use crate::source::{read_capped, resolve_inside};
use crate::validate::MAX_OBJ_BYTES;
use std::path::{Path, PathBuf};

use glam::Vec3;
use gltf::accessor::{DataType, Dimensions};

/// Every buffer's bytes, cut to its declared length.
pub(super) fn read_buffers(
    doc: &gltf::Gltf,
    file: &str,
    folders: Option<(&Path, &Path)>,
    mut total: u64,
    files: &mut Vec<PathBuf>,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let what = match buffer.name() {
            Some(n) => format!("buffer {i} (\"{n}\")"),
            None => format!("buffer {i}"),
        };
        let mut data = match buffer.source() {
            gltf::buffer::Source::Bin => doc.blob.clone().ok_or_else(|| {
                fail(
                    file,
                    format_args!("{what} is the GLB binary chunk, which the file does not have"),
                    "write a GLB file with its BIN chunk",
                )
            })?,
            gltf::buffer::Source::Uri(uri) => read_uri(uri, file, &what, folders, files)?,
        };
        total = total.saturating_add(data.len() as u64);
        if total > MAX_GLTF_BYTES {
            return Err(fail(
                file,
                format_args!("its buffers reach {total} bytes with {what}, above the limit of {MAX_GLTF_BYTES}"),
                "use a smaller scene",
            ));
        }
        if data.len() < buffer.length() {
            return Err(fail(
                file,
                format_args!("{what} declares {} bytes but holds {}", buffer.length(), data.len()),
                "write the buffer's true byteLength",
            ));
        }
        data.truncate(buffer.length());
        out.push(data);
    }
    Ok(out)
}

fn read_uri(uri: &str, file: &str, what: &str, folders: Option<(&Path, &Path)>, files: &mut Vec<PathBuf>) -> Result<Vec<u8>, SceneError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        use base64::Engine;
        let Some((_, payload)) = rest.split_once(";base64,") else {
            return Err(fail(
                file,
                format_args!("{what} is a data URI that is not base64"),
                "write `data:application/octet-stream;base64,...`",
            ));
        };
        return base64::engine::general_purpose::STANDARD.decode(payload).map_err(|e| {
            fail(
                file,
                format_args!("{what}'s data URI is not valid base64: {e}"),
                "write the buffer as standard base64",
            )
        });
    }
    if uri.contains("://") {
        return Err(fail(
            file,
            format_args!("{what} is at `{uri}`: sshc reads no network address"),
            "put the buffer beside the glTF file, or write a GLB",
        ));
    }
    let Some((scene_folder, gltf_folder)) = folders else {
        return Err(fail(
            file,
            format_args!("{what} is the file `{uri}`, and this glTF has no folder to read it from"),
            "write a GLB, or embed the buffer as a data URI",
        ));
    };
    let decoded = percent_encoding::percent_decode_str(uri).decode_utf8().map_err(|_| {
        fail(
            file,
            format_args!("{what}'s URI `{uri}` is not UTF-8 once decoded"),
            "name the buffer file in UTF-8",
        )
    })?;
    // relative to the glTF's folder, which lies inside the scene folder
    let rel_to_scene = gltf_folder
        .strip_prefix(scene_folder)
        .map(|f| f.join(decoded.as_ref()))
        .unwrap_or_else(|_| PathBuf::from(decoded.as_ref()));
    let rel = rel_to_scene.to_string_lossy().into_owned();
    let path =
        resolve_inside(&rel, scene_folder).map_err(|e| fail(file, format_args!("{what}: {}", e.message()), e.hint().unwrap_or("")))?;
    let data = read_capped(&path, MAX_OBJ_BYTES).map_err(|e| {
        fail(
            file,
            format_args!("cannot read {what} `{}`: {e}", path.display()),
            "check that the buffer file is beside the glTF file",
        )
    })?;
    files.push(path);
    Ok(data)
}

/// The bytes of an accessor's `count` elements of `size` bytes: (data, stride, count).
fn accessor_bytes<'b>(a: &gltf::Accessor, buffers: &'b [Vec<u8>], file: &str, what: &str) -> Result<(&'b [u8], usize, usize), SceneError> {
    let bad = |m: String| {
        fail(
            file,
            format_args!("{what} (accessor {}): {m}", a.index()),
            "check the accessor against its buffer view",
        )
    };
    if a.sparse().is_some() {
        return Err(bad("sparse accessors are not read".into()));
    }
    let Some(view) = a.view() else {
        return Err(bad("it has no buffer view".into()));
    };
    let data = buffers
        .get(view.buffer().index())
        .ok_or_else(|| bad("its buffer is missing".into()))?;
    let view_bytes = view
        .offset()
        .checked_add(view.length())
        .and_then(|end| data.get(view.offset()..end))
        .ok_or_else(|| {
            bad(format!(
                "its buffer view {} lies outside its buffer of {} bytes",
                view.index(),
                data.len()
            ))
        })?;
    let size = a.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(bad(format!("its stride of {stride} bytes is below its element size of {size}")));
    }
    let count = a.count();
    if count == 0 {
        return Ok((&[], stride, 0));
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|n| n.checked_add(size))
        .and_then(|n| n.checked_add(a.offset()));
    match end {
        Some(end) if end <= view_bytes.len() => Ok((&view_bytes[a.offset()..end], stride, count)),
        _ => Err(bad(format!(
            "{count} elements from byte {} are out of range of buffer view {} ({} bytes)",
            a.offset(),
            view.index(),
            view_bytes.len()
        ))),
    }
}

pub(super) fn read_vec3(a: &gltf::Accessor, buffers: &[Vec<u8>], file: &str, what: &str) -> Result<Vec<Vec3>, SceneError> {
    if a.data_type() != DataType::F32 || a.dimensions() != Dimensions::Vec3 || a.normalized() {
        return Err(fail(
            file,
            format_args!(
                "{what} (accessor {}) is {:?} {:?}, not VEC3 FLOAT",
                a.index(),
                a.dimensions(),
                a.data_type()
            ),
            "store positions and normals as 32-bit floats (no quantisation)",
        ));
    }
    let (bytes, stride, count) = accessor_bytes(a, buffers, file, what)?;
    let f = |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    Ok((0..count)
        .map(|k| k * stride)
        .map(|o| Vec3::new(f(o), f(o + 4), f(o + 8)))
        .collect())
}

pub(super) fn read_indices(a: &gltf::Accessor, buffers: &[Vec<u8>], file: &str, what: &str) -> Result<Vec<u32>, SceneError> {
    let width = match (a.data_type(), a.dimensions()) {
        (DataType::U8, Dimensions::Scalar) => 1,
        (DataType::U16, Dimensions::Scalar) => 2,
        (DataType::U32, Dimensions::Scalar) => 4,
        (t, d) => {
            return Err(fail(
                file,
                format_args!("{what} (accessor {}) is {d:?} {t:?}, not an unsigned integer scalar", a.index()),
                "store indices as UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT scalars",
            ));
        }
    };
    let (bytes, stride, count) = accessor_bytes(a, buffers, file, what)?;
    Ok((0..count)
        .map(|k| {
            let o = k * stride;
            match width {
                1 => u32::from(bytes[o]),
                2 => u32::from(u16::from_le_bytes([bytes[o], bytes[o + 1]])),
                _ => u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]),
            }
        })
        .collect())
}
