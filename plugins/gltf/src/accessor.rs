//! Accessors decoded into vectors, with every byte range checked before it is read:
//! offset, stride and count against the buffer view, sparse indices and values against
//! theirs, and counts against the host's `--max-triangles`
//! ([`kiln_plugin_api::max_triangles`]). Normalised integers are mapped as the
//! spec's §3.11 equations say, so quantised attributes (`KHR_mesh_quantization`) read
//! like floats.
//!
//! Matrices are not read: no attribute Kiln uses has one.

use gltf::json;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;

use crate::buffers::Buffers;

/// Elements an accessor without a buffer view (zeros, perhaps with sparse values) may
/// claim: such counts are not backed by bytes in the file.
pub const MAX_UNBACKED_ELEMENTS: u64 = 1 << 20;

/// What an accessor decodes into.
pub trait Element: Copy {
    const COMPONENTS: usize;
    fn zero() -> Self;
    fn accepts(component: ComponentType) -> bool;
    /// `bytes` holds exactly one element.
    fn decode(bytes: &[u8], component: ComponentType, normalized: bool) -> Self;
}

fn component_size(c: ComponentType) -> usize {
    match c {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

fn type_components(t: Type) -> usize {
    match t {
        Type::Scalar => 1,
        Type::Vec2 => 2,
        Type::Vec3 => 3,
        Type::Vec4 | Type::Mat2 => 4,
        Type::Mat3 => 9,
        Type::Mat4 => 16,
    }
}

/// One component as stored (integers as integers).
pub(crate) fn component(b: &[u8], c: ComponentType) -> f64 {
    match c {
        ComponentType::I8 => f64::from(b[0] as i8),
        ComponentType::U8 => f64::from(b[0]),
        ComponentType::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
        ComponentType::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
        ComponentType::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        ComponentType::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
    }
}

/// A stored value as the accessor means it (glTF 2.0 §3.11 for normalised integers;
/// normalised UNSIGNED_INT is not allowed, and reads as its value).
pub(crate) fn normalize(v: f64, c: ComponentType, normalized: bool) -> f64 {
    if !normalized {
        return v;
    }
    match c {
        ComponentType::I8 => (v / 127.0).max(-1.0),
        ComponentType::U8 => v / 255.0,
        ComponentType::I16 => (v / 32767.0).max(-1.0),
        ComponentType::U16 => v / 65535.0,
        _ => v,
    }
}

/// One component as a float.
fn decode_float(b: &[u8], c: ComponentType, normalized: bool) -> f32 {
    normalize(component(b, c), c, normalized) as f32
}

fn decode_index(b: &[u8], c: ComponentType) -> u32 {
    match c {
        ComponentType::U8 => b[0] as u32,
        ComponentType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

impl<const N: usize> Element for [f32; N] {
    const COMPONENTS: usize = N;
    fn zero() -> Self {
        [0.0; N]
    }
    fn accepts(_: ComponentType) -> bool {
        true
    }
    fn decode(bytes: &[u8], component: ComponentType, normalized: bool) -> Self {
        let size = component_size(component);
        std::array::from_fn(|i| decode_float(&bytes[i * size..], component, normalized))
    }
}

impl Element for u32 {
    const COMPONENTS: usize = 1;
    fn zero() -> Self {
        0
    }
    fn accepts(component: ComponentType) -> bool {
        matches!(
            component,
            ComponentType::U8 | ComponentType::U16 | ComponentType::U32
        )
    }
    fn decode(bytes: &[u8], component: ComponentType, _: bool) -> Self {
        decode_index(bytes, component)
    }
}

/// The number of components of accessor `index` (1 for SCALAR, 3 for VEC3, …).
pub fn components(root: &json::Root, index: usize) -> Option<usize> {
    match root.accessors.get(index)?.type_ {
        Checked::Valid(t) => Some(type_components(t)),
        Checked::Invalid => None,
    }
}

/// `count` elements of `size` bytes `stride` apart from `offset`: the byte range they
/// span, if it fits in `available` bytes.
fn span(
    offset: u64,
    stride: u64,
    count: u64,
    size: u64,
    available: usize,
) -> Option<(usize, usize)> {
    if count == 0 {
        return Some((0, 0));
    }
    let end = stride
        .checked_mul(count - 1)?
        .checked_add(size)?
        .checked_add(offset)?;
    (end <= available as u64).then_some((offset as usize, end as usize))
}

/// Decodes accessor `index` as elements of type `T`.
pub fn read<T: Element>(
    root: &json::Root,
    buffers: &Buffers,
    index: usize,
) -> Result<Vec<T>, String> {
    let fail = |m: String| format!("accessor {index}: {m}");
    let accessor = root
        .accessors
        .get(index)
        .ok_or_else(|| format!("accessor {index} does not exist"))?;
    let Checked::Valid(json::accessor::GenericComponentType(component)) = accessor.component_type
    else {
        return Err(fail("invalid componentType".into()));
    };
    let Checked::Valid(kind) = accessor.type_ else {
        return Err(fail("invalid type".into()));
    };
    if !T::accepts(component) {
        return Err(fail(format!(
            "componentType {component:?} is not allowed here"
        )));
    }
    if matches!(kind, Type::Mat2 | Type::Mat3 | Type::Mat4)
        || type_components(kind) != T::COMPONENTS
    {
        return Err(fail(format!(
            "type {kind:?} where {} components were expected",
            T::COMPONENTS
        )));
    }
    let count = accessor.count.0;
    // The host's limit on a whole import: one accessor past it could never be taken.
    let max = kiln_plugin_api::max_triangles();
    if count > max {
        return Err(fail(format!(
            "{count} elements (at most {max} are read; --max-triangles raises the limit)"
        )));
    }
    let size = component_size(component) * T::COMPONENTS;
    let mut out: Vec<T>;
    match accessor.buffer_view {
        Some(view) => {
            let (bytes, stride) = buffers.view(root, view.value()).map_err(&fail)?;
            let stride = stride.unwrap_or(size);
            if stride < size {
                return Err(fail(format!(
                    "byteStride {stride} is smaller than an element ({size} bytes)"
                )));
            }
            let offset = accessor.byte_offset.map_or(0, |o| o.0);
            let Some((start, _)) = span(offset, stride as u64, count, size as u64, bytes.len())
            else {
                return Err(fail(format!(
                    "{count} elements of {size} bytes, {stride} apart from offset {offset}, do not fit in buffer view {} of {} bytes",
                    view.value(),
                    bytes.len()
                )));
            };
            out = (0..count as usize)
                .map(|i| {
                    let at = start + i * stride;
                    T::decode(&bytes[at..at + size], component, accessor.normalized)
                })
                .collect();
        }
        None => {
            if count > MAX_UNBACKED_ELEMENTS {
                return Err(fail(format!(
                    "{count} elements without a buffer view (at most {MAX_UNBACKED_ELEMENTS} are read)"
                )));
            }
            out = vec![T::zero(); count as usize];
        }
    }
    if let Some(sparse) = &accessor.sparse {
        apply_sparse(
            root,
            buffers,
            sparse,
            component,
            accessor.normalized,
            size,
            &mut out,
        )
        .map_err(|m| fail(format!("sparse: {m}")))?;
    }
    Ok(out)
}

fn apply_sparse<T: Element>(
    root: &json::Root,
    buffers: &Buffers,
    sparse: &json::accessor::sparse::Sparse,
    component: ComponentType,
    normalized: bool,
    size: usize,
    out: &mut [T],
) -> Result<(), String> {
    let count = sparse.count.0;
    if count > out.len() as u64 {
        return Err(format!(
            "{count} values for an accessor of {} elements",
            out.len()
        ));
    }
    let Checked::Valid(json::accessor::IndexComponentType(index_type)) =
        sparse.indices.component_type
    else {
        return Err("invalid index componentType".into());
    };
    if !u32::accepts(index_type) {
        return Err(format!("index componentType {index_type:?} is not allowed"));
    }
    let index_size = component_size(index_type);
    let (index_bytes, _) = buffers.view(root, sparse.indices.buffer_view.value())?;
    let index_offset = sparse.indices.byte_offset.0;
    let (index_start, _) = span(
        index_offset,
        index_size as u64,
        count,
        index_size as u64,
        index_bytes.len(),
    )
    .ok_or_else(|| {
        format!("{count} indices from offset {index_offset} do not fit in their buffer view")
    })?;
    let (value_bytes, _) = buffers.view(root, sparse.values.buffer_view.value())?;
    let value_offset = sparse.values.byte_offset.0;
    let (value_start, _) = span(
        value_offset,
        size as u64,
        count,
        size as u64,
        value_bytes.len(),
    )
    .ok_or_else(|| {
        format!("{count} values from offset {value_offset} do not fit in their buffer view")
    })?;
    for i in 0..count as usize {
        let at = index_start + i * index_size;
        let target = decode_index(&index_bytes[at..at + index_size], index_type) as usize;
        let at = value_start + i * size;
        let value = T::decode(&value_bytes[at..at + size], component, normalized);
        let len = out.len();
        *out.get_mut(target)
            .ok_or_else(|| format!("index {target} is out of range ({len} elements)"))? = value;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root_with(accessor: &str, view: &str, buffer_bytes: &[u8]) -> (json::Root, Buffers) {
        use base64::Engine;
        let data = base64::engine::general_purpose::STANDARD.encode(buffer_bytes);
        let text = format!(
            r#"{{"asset":{{"version":"2.0"}},
                "buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{data}"}}],
                "bufferViews":[{view}],
                "accessors":[{accessor}]}}"#,
            buffer_bytes.len()
        );
        let root: json::Root = json::deserialize::from_str(&text).expect("test JSON");
        let buffers = Buffers::load(&root, std::path::Path::new("."), None).expect("buffers");
        (root, buffers)
    }

    #[test]
    fn normalized_shorts_map_to_minus_one_one() {
        let bytes: Vec<u8> = [i16::MIN, -32767, 0, 32767]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let (root, buffers) = root_with(
            r#"{"bufferView":0,"componentType":5122,"count":2,"type":"VEC2","normalized":true}"#,
            r#"{"buffer":0,"byteLength":8}"#,
            &bytes,
        );
        let v: Vec<[f32; 2]> = read(&root, &buffers, 0).expect("readable");
        assert_eq!(v, vec![[-1.0, -1.0], [0.0, 1.0]]);
    }

    #[test]
    fn strided_normalized_bytes_read_each_element() {
        let (root, buffers) = root_with(
            r#"{"bufferView":0,"componentType":5121,"normalized":true,"count":3,"type":"VEC3"}"#,
            r#"{"buffer":0,"byteLength":12,"byteStride":4}"#,
            &[255, 0, 0, 0, 0, 255, 0, 0, 0, 0, 255, 0],
        );
        let v: Vec<[f32; 3]> = read(&root, &buffers, 0).expect("readable");
        assert_eq!(v, vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    }

    #[test]
    fn strided_accessor_past_its_view_is_refused() {
        let (root, buffers) = root_with(
            r#"{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}"#,
            r#"{"buffer":0,"byteLength":32,"byteStride":16}"#,
            &[0u8; 32],
        );
        let e = read::<[f32; 3]>(&root, &buffers, 0).expect_err("two elements fit, not three");
        assert!(e.contains("do not fit"), "{e}");
    }

    #[test]
    fn sparse_values_override_zeros() {
        let mut bytes = vec![1u8, 0, 0, 0];
        bytes.extend_from_slice(&5.0f32.to_le_bytes());
        let (root, buffers) = root_with(
            r#"{"componentType":5126,"count":3,"type":"SCALAR",
                "sparse":{"count":1,"indices":{"bufferView":0,"componentType":5121},
                          "values":{"bufferView":0,"byteOffset":4}}}"#,
            r#"{"buffer":0,"byteLength":8}"#,
            &bytes,
        );
        let v: Vec<[f32; 1]> = read(&root, &buffers, 0).expect("readable");
        assert_eq!(v, vec![[0.0], [5.0], [0.0]]);
    }

    #[test]
    fn sparse_index_out_of_range_is_refused() {
        let mut bytes = vec![9u8, 0, 0, 0];
        bytes.extend_from_slice(&5.0f32.to_le_bytes());
        let (root, buffers) = root_with(
            r#"{"componentType":5126,"count":3,"type":"SCALAR",
                "sparse":{"count":1,"indices":{"bufferView":0,"componentType":5121},
                          "values":{"bufferView":0,"byteOffset":4}}}"#,
            r#"{"buffer":0,"byteLength":8}"#,
            &bytes,
        );
        assert!(read::<[f32; 1]>(&root, &buffers, 0).is_err());
    }

    #[test]
    fn float_indices_are_refused() {
        let (root, buffers) = root_with(
            r#"{"bufferView":0,"componentType":5126,"count":1,"type":"SCALAR"}"#,
            r#"{"buffer":0,"byteLength":4}"#,
            &[0u8; 4],
        );
        assert!(read::<u32>(&root, &buffers, 0).is_err());
    }
}
