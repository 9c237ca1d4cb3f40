//! Checks of accessor values, read as stored (sparse substitution applied): NaN and
//! infinities (ACCESSOR_INVALID_FLOAT), values outside the declared min/max and declared
//! bounds that are not the data's (ACCESSOR_ELEMENT_OUT_OF_MIN_BOUND / _MAX_BOUND,
//! ACCESSOR_MIN_MISMATCH / _MAX_MISMATCH), sparse indices out of order or range
//! (ACCESSOR_SPARSE_INDICES_NON_INCREASING, ACCESSOR_SPARSE_INDEX_OOB), and by use:
//! normals and tangents that are not unit vectors (ACCESSOR_VECTOR3_NON_UNIT), tangent
//! signs other than ±1 (ACCESSOR_INVALID_SIGN), float colours outside [0, 1]
//! (ACCESSOR_NON_CLAMPED), indices past the vertices or equal to the primitive-restart
//! value (ACCESSOR_INDEX_OOB, ACCESSOR_INDEX_PRIMITIVE_RESTART), and inverse bind
//! matrices whose last row is not (0, 0, 0, 1) (ACCESSOR_INVALID_IBM).
//!
//! Accessors whose bytes cannot be read are left to [`super::structure`] and the readers;
//! accessors without a buffer view or sparse values (zeros) are not checked.

use gltf::json;
use gltf::json::Value;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;

use super::{MAX_ELEMENTS_SCANNED, MAX_VALUES_SCANNED, Report, Uses, list};
use crate::accessor::{component, normalize};
use crate::buffers::Buffers;

/// Tolerance on the length of unit vectors (the validator's: a little more than the error
/// of 8-bit quantisation).
const UNIT_TOLERANCE: f64 = 0.00674;

/// How an accessor's elements lie in memory.
#[derive(Clone, Copy, Debug)]
pub struct Layout {
    pub component: ComponentType,
    pub component_size: usize,
    /// Components per element (16 for MAT4).
    pub components: usize,
    /// Components per column: `components` except for matrices.
    pub rows: usize,
    /// Bytes from one matrix column to the next (columns start on 4-byte boundaries).
    pub column_stride: usize,
    /// Bytes one element spans, without the padding after its last column.
    pub element_length: usize,
    /// The distance between elements when the buffer view gives no stride.
    pub default_stride: usize,
}

impl Layout {
    pub fn of(accessor: &json::Accessor) -> Option<Self> {
        let Checked::Valid(json::accessor::GenericComponentType(component)) =
            accessor.component_type
        else {
            return None;
        };
        let Checked::Valid(kind) = accessor.type_ else {
            return None;
        };
        let (rows, columns) = match kind {
            Type::Scalar => (1, 1),
            Type::Vec2 => (2, 1),
            Type::Vec3 => (3, 1),
            Type::Vec4 => (4, 1),
            Type::Mat2 => (2, 2),
            Type::Mat3 => (3, 3),
            Type::Mat4 => (4, 4),
        };
        let size = component.size();
        let column_stride = if columns > 1 {
            (rows * size + 3) & !3
        } else {
            rows * size
        };
        Some(Self {
            component,
            component_size: size,
            components: rows * columns,
            rows,
            column_stride,
            element_length: (columns - 1) * column_stride + rows * size,
            default_stride: columns * column_stride,
        })
    }

    pub fn is_matrix(&self) -> bool {
        self.rows != self.components
    }

    /// Bytes `count` elements `stride` apart span.
    pub fn byte_length(&self, count: u64, stride: u64) -> u64 {
        if count == 0 {
            return 0;
        }
        stride
            .saturating_mul(count - 1)
            .saturating_add(self.element_length as u64)
    }

    /// Where component `k` of an element starts.
    fn offset_of(&self, k: usize) -> usize {
        (k / self.rows) * self.column_stride + (k % self.rows) * self.component_size
    }

    /// Element at the start of `bytes` (which holds at least `element_length` bytes).
    fn decode(&self, bytes: &[u8], out: &mut [f64; 16]) {
        for (k, v) in out.iter_mut().enumerate().take(self.components) {
            *v = component(&bytes[self.offset_of(k)..], self.component);
        }
    }
}

/// What a scan read.
struct Scanned {
    /// Elements visited (the first ones).
    elements: u64,
    /// Problems of the sparse indices.
    sparse: Vec<String>,
}

/// Calls `visit(i, components)` for the first `limit` elements of accessor `index`.
/// None if its bytes cannot be read or it is all zeros (no buffer view, no sparse).
fn scan(
    root: &json::Root,
    buffers: &Buffers,
    index: usize,
    layout: &Layout,
    limit: u64,
    visit: &mut dyn FnMut(u64, &[f64]),
) -> Option<Scanned> {
    let accessor = root.accessors.get(index)?;
    let count = accessor.count.0;
    let n = count.min(limit);
    let base = match accessor.buffer_view {
        Some(v) => {
            let (bytes, stride) = buffers.view(root, v.value()).ok()?;
            let stride = stride.unwrap_or(layout.default_stride);
            if stride < layout.element_length {
                return None;
            }
            let offset = accessor.byte_offset.map_or(0, |o| o.0);
            let end = offset.checked_add(layout.byte_length(count, stride as u64))?;
            if end > bytes.len() as u64 {
                return None;
            }
            Some((bytes, offset as usize, stride))
        }
        None if accessor.sparse.is_some() => None,
        None => return None,
    };
    let mut sparse_problems = Vec::new();
    let mut substitutes: Vec<(u64, usize)> = Vec::new();
    let mut values: &[u8] = &[];
    if let Some(sparse) = &accessor.sparse {
        let sparse_count = sparse.count.0;
        if sparse_count > count {
            return None;
        }
        let Checked::Valid(json::accessor::IndexComponentType(index_type)) =
            sparse.indices.component_type
        else {
            return None;
        };
        let index_size = index_type.size();
        let (index_bytes, _) = buffers
            .view(root, sparse.indices.buffer_view.value())
            .ok()?;
        let (value_bytes, _) = buffers.view(root, sparse.values.buffer_view.value()).ok()?;
        let at = sparse.indices.byte_offset.0;
        let value_at = sparse.values.byte_offset.0;
        let element = (layout.components * layout.component_size) as u64;
        let fits = |at: u64, size: u64, bytes: &[u8]| {
            size.checked_mul(sparse_count)
                .and_then(|l| l.checked_add(at))
                .is_some_and(|end| end <= bytes.len() as u64)
        };
        if !fits(at, index_size as u64, index_bytes) || !fits(value_at, element, value_bytes) {
            return None;
        }
        values = &value_bytes[value_at as usize..];
        let index_bytes = &index_bytes[at as usize..];
        let read = sparse_count.min(MAX_ELEMENTS_SCANNED) as usize;
        let (mut out_of_order, mut out_of_range) = (0u64, 0u64);
        let mut previous: Option<u64> = None;
        for position in 0..read {
            let b = &index_bytes[position * index_size..];
            let i = component(b, index_type) as u64;
            if previous.is_some_and(|p| i <= p) {
                out_of_order += 1;
            }
            previous = Some(i);
            if i >= count {
                out_of_range += 1;
            } else {
                substitutes.push((i, position));
            }
        }
        if out_of_order > 0 {
            sparse_problems.push(format!(
                "its sparse indices are not strictly increasing ({out_of_order} out of order)"
            ));
        }
        if out_of_range > 0 {
            sparse_problems.push(format!(
                "{out_of_range} sparse indices are past its {count} elements"
            ));
        }
        // Later entries win where an index repeats.
        substitutes.sort_by_key(|&(i, _)| i);
    }
    let value_size = layout.components * layout.component_size;
    let sparse_layout = Layout {
        rows: layout.components,
        column_stride: value_size,
        ..*layout
    };
    let mut element = [0.0f64; 16];
    let mut next = 0;
    for i in 0..n {
        let mut substituted = None;
        while next < substitutes.len() && substitutes[next].0 == i {
            substituted = Some(substitutes[next].1);
            next += 1;
        }
        match (substituted, base) {
            // Sparse values are tightly packed, without matrix column padding.
            (Some(position), _) => {
                sparse_layout.decode(&values[position * value_size..], &mut element)
            }
            (None, Some((bytes, offset, stride))) => {
                layout.decode(&bytes[offset + i as usize * stride..], &mut element)
            }
            (None, None) => element = [0.0; 16],
        }
        visit(i, &element[..layout.components]);
    }
    Some(Scanned {
        elements: n,
        sparse: sparse_problems,
    })
}

/// The declared min or max of an accessor as the data would have it (floats at single
/// precision), if it is an array of the right length.
fn bound(value: Option<&Value>, layout: &Layout) -> Option<Vec<f64>> {
    let items = value?.as_array()?;
    if items.len() != layout.components {
        return None;
    }
    items
        .iter()
        .map(|v| {
            let v = v.as_f64()?;
            Some(if layout.component == ComponentType::F32 {
                f64::from(v as f32)
            } else {
                v
            })
        })
        .collect()
}

fn numbers(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| format!("{x}")).collect();
    format!("[{}]", items.join(", "))
}

/// What the scan of one accessor found.
#[derive(Default)]
struct Findings {
    non_finite: u64,
    first_non_finite: Option<u64>,
    below_min: u64,
    above_max: u64,
    min: Vec<f64>,
    max: Vec<f64>,
    non_unit: u64,
    first_non_unit: Option<(u64, f64)>,
    bad_sign: u64,
    unclamped: u64,
    index_past: u64,
    first_index_past: Option<(u64, u64)>,
    restart: u64,
    bad_ibm: u64,
}

pub fn check(root: &json::Root, buffers: &Buffers, uses: &Uses, report: &mut Report) {
    let mut budget = MAX_VALUES_SCANNED;
    let mut unchecked = Vec::new();
    let mut reported = false;
    for (index, accessor) in root.accessors.iter().enumerate() {
        let Some(layout) = Layout::of(accessor) else {
            continue;
        };
        let roles = uses.accessor_roles.get(index).copied().unwrap_or_default();
        let float = layout.component == ComponentType::F32;
        let min = bound(accessor.min.as_ref(), &layout);
        let max = bound(accessor.max.as_ref(), &layout);
        let vector3 = (roles.normal || roles.tangent) && layout.rows >= 3 && !layout.is_matrix();
        let sign = roles.tangent && layout.components == 4;
        let color = roles.color && float && !layout.is_matrix();
        let indices = roles.indices && layout.components == 1 && !float;
        let ibm = roles.inverse_bind_matrices && float && layout.components == 16;
        if !(float || min.is_some() || max.is_some() || indices) {
            continue;
        }
        if budget < layout.components as u64 {
            unchecked.push(index);
            continue;
        }
        let limit = MAX_ELEMENTS_SCANNED.min(budget / layout.components as u64);
        let restart = match layout.component {
            ComponentType::U8 => 255.0,
            ComponentType::U16 => 65535.0,
            _ => 4_294_967_295.0,
        };
        let index_limit = uses.index_limit.get(index).copied().flatten();
        let normalized = accessor.normalized;
        let mut f = Findings {
            min: vec![f64::INFINITY; layout.components],
            max: vec![f64::NEG_INFINITY; layout.components],
            ..Findings::default()
        };
        let mut visit = |i: u64, v: &[f64]| {
            if float && v.iter().any(|x| !x.is_finite()) {
                f.non_finite += 1;
                f.first_non_finite.get_or_insert(i);
            }
            for (k, &x) in v.iter().enumerate() {
                if x.is_nan() {
                    continue;
                }
                f.min[k] = f.min[k].min(x);
                f.max[k] = f.max[k].max(x);
            }
            if let Some(lo) = &min {
                if v.iter().zip(lo).any(|(x, l)| x < l) {
                    f.below_min += 1;
                }
            }
            if let Some(hi) = &max {
                if v.iter().zip(hi).any(|(x, h)| x > h) {
                    f.above_max += 1;
                }
            }
            if vector3 {
                let n = |k: usize| normalize(v[k], layout.component, normalized);
                let length = (n(0) * n(0) + n(1) * n(1) + n(2) * n(2)).sqrt();
                if length.is_nan() || (length - 1.0).abs() > UNIT_TOLERANCE {
                    f.non_unit += 1;
                    f.first_non_unit.get_or_insert((i, length));
                }
            }
            if sign {
                let w = normalize(v[3], layout.component, normalized);
                if w != 1.0 && w != -1.0 {
                    f.bad_sign += 1;
                }
            }
            if color && v.iter().any(|x| !(0.0..=1.0).contains(x)) {
                f.unclamped += 1;
            }
            if indices {
                let x = v[0];
                if x == restart {
                    f.restart += 1;
                } else if index_limit.is_some_and(|n| x >= n as f64) {
                    f.index_past += 1;
                    f.first_index_past.get_or_insert((i, x as u64));
                }
            }
            if ibm && (v[3] != 0.0 || v[7] != 0.0 || v[11] != 0.0 || v[15] != 1.0) {
                f.bad_ibm += 1;
            }
        };
        let Some(scanned) = scan(root, buffers, index, &layout, limit, &mut visit) else {
            continue;
        };
        budget = budget.saturating_sub(scanned.elements * layout.components as u64);
        let total = accessor.count.0;
        let complete = scanned.elements == total;
        let mut problems = scanned.sparse;
        if f.non_finite > 0 {
            problems.push(format!(
                "{} element(s) hold NaN or infinity (the first at index {})",
                f.non_finite,
                f.first_non_finite.unwrap_or(0)
            ));
        }
        if f.below_min > 0 {
            problems.push(format!("{} element(s) below its declared min", f.below_min));
        }
        if f.above_max > 0 {
            problems.push(format!("{} element(s) above its declared max", f.above_max));
        }
        if complete && total > 0 {
            let mismatch = |declared: &Option<Vec<f64>>, actual: &[f64]| {
                declared
                    .as_ref()
                    .filter(|d| d.iter().zip(actual).any(|(d, a)| a.is_finite() && d != a))
                    .map(|d| (numbers(d), numbers(actual)))
            };
            if let Some((d, a)) = mismatch(&min, &f.min) {
                problems.push(format!("declared min {d} is not the data's, {a}"));
            }
            if let Some((d, a)) = mismatch(&max, &f.max) {
                problems.push(format!("declared max {d} is not the data's, {a}"));
            }
        }
        if f.non_unit > 0 {
            let (i, length) = f.first_non_unit.unwrap_or((0, 0.0));
            problems.push(format!(
                "{} vector(s) are not of unit length (element {i}: {length:.4})",
                f.non_unit
            ));
        }
        if f.bad_sign > 0 {
            problems.push(format!(
                "{} tangent(s) have a w (handedness) other than 1 or -1",
                f.bad_sign
            ));
        }
        if f.unclamped > 0 {
            problems.push(format!(
                "{} colour(s) have components outside [0, 1]",
                f.unclamped
            ));
        }
        if f.index_past > 0 {
            let (i, v) = f.first_index_past.unwrap_or((0, 0));
            problems.push(format!(
                "{} index(es) point past the primitive's {} vertices (element {i}: {v})",
                f.index_past,
                index_limit.unwrap_or(0)
            ));
        }
        if f.restart > 0 {
            problems.push(format!(
                "{} index(es) equal the primitive-restart value {restart}, which glTF forbids",
                f.restart
            ));
        }
        if f.bad_ibm > 0 {
            problems.push(format!(
                "{} inverse bind matri(ces) have a last row other than (0, 0, 0, 1)",
                f.bad_ibm
            ));
        }
        if !problems.is_empty() {
            let note = if complete {
                String::new()
            } else {
                format!(
                    " (checked the first {} of {total} elements only)",
                    scanned.elements
                )
            };
            reported = true;
            report.add(format!(
                "{}: {}{note}",
                uses.accessor(root, index),
                problems.join("; ")
            ));
        }
    }
    // Said only next to problems found, which it qualifies: on a large valid file it
    // would be noise.
    if !unchecked.is_empty() && reported {
        report.add(format!(
            "the values of accessor(s) {} were not checked (the file has more than the {MAX_VALUES_SCANNED} values checked per import), so the value problems above may not be all",
            list(&unchecked, 6)
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout(component: u32, kind: &str) -> Layout {
        let accessor: json::Accessor = json::deserialize::from_str(&format!(
            r#"{{"componentType":{component},"count":1,"type":"{kind}"}}"#
        ))
        .expect("accessor JSON");
        Layout::of(&accessor).expect("valid layout")
    }

    #[test]
    fn matrix_columns_are_padded_to_four_bytes() {
        let m3 = layout(5121, "MAT3");
        assert_eq!(
            (m3.column_stride, m3.element_length, m3.default_stride),
            (4, 11, 12)
        );
        assert_eq!(m3.offset_of(4), 5);
        let m2 = layout(5121, "MAT2");
        assert_eq!((m2.element_length, m2.default_stride), (6, 8));
        let m3s = layout(5123, "MAT3");
        assert_eq!((m3s.element_length, m3s.default_stride), (22, 24));
        let m4 = layout(5126, "MAT4");
        assert_eq!((m4.element_length, m4.default_stride), (64, 64));
        let v3 = layout(5126, "VEC3");
        assert_eq!((v3.element_length, v3.offset_of(2)), (12, 8));
        assert!(!v3.is_matrix() && m4.is_matrix());
    }
}
