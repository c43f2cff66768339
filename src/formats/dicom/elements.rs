//! The values of a parsed header's elements: text, numbers and sequence items, read alike whether
//! the element has its own VR or some converter stored it as UN (unknown).

use dicom_core::{Tag, VR};
use dicom_object::InMemDicomObject;

/// The text of element `tag`: its value as a string, or, for a value some converter stored as
/// UN (unknown), its bytes read as text (as dcmtk and pydicom read them).
pub(super) fn text(obj: &InMemDicomObject, tag: Tag) -> Option<String> {
    let e = obj.get(tag)?;
    let t = if e.vr() == VR::UN {
        String::from_utf8_lossy(e.to_bytes().ok()?.as_ref()).into_owned()
    } else {
        e.to_str().ok()?.into_owned()
    };
    let t = t.trim_matches(|c: char| c == '\0' || c.is_whitespace());
    (!t.is_empty()).then(|| t.to_string())
}

/// [`text`] as outputs show it: escaped by the one rule of [`crate::error::names`], so that a
/// field's control characters never reach a terminal (and keys and labels agree everywhere).
pub(super) fn shown_text(obj: &InMemDicomObject, tag: Tag) -> Option<String> {
    text(obj, tag).map(|t| crate::error::names::text(&t))
}

/// The numbers of element `tag` (of a value stored as UN, its text split at backslashes), when
/// all are finite.
pub(super) fn floats(obj: &InMemDicomObject, tag: Tag) -> Option<Vec<f64>> {
    let e = obj.get(tag)?;
    let v = if e.vr() == VR::UN {
        text(obj, tag)?
            .split('\\')
            .map(|x| x.trim().parse::<f64>().ok())
            .collect::<Option<Vec<f64>>>()?
    } else {
        e.to_multi_float64().ok()?
    };
    v.iter().all(|x| x.is_finite()).then_some(v)
}

/// The first of [`floats`].
pub(super) fn float(obj: &InMemDicomObject, tag: Tag) -> Option<f64> {
    floats(obj, tag)?.first().copied()
}

/// The integer of element `tag` (of a value stored as UN, its text's first).
pub(super) fn int(obj: &InMemDicomObject, tag: Tag) -> Option<i64> {
    let e = obj.get(tag)?;
    if e.vr() == VR::UN {
        return text(obj, tag)?.split('\\').next()?.trim().parse().ok();
    }
    e.to_int::<i64>().ok()
}

/// The unsigned 16-bit integer of element `tag`.
pub(super) fn uint(obj: &InMemDicomObject, tag: Tag) -> Option<u16> {
    obj.get(tag)?.to_int::<u16>().ok()
}

/// The first item of the sequence `tag` in `obj`.
pub(super) fn item(obj: &InMemDicomObject, tag: Tag) -> Option<&InMemDicomObject> {
    obj.get(tag)?.items()?.first()
}

/// The first `N` numbers of `v`, when it has as many.
pub(super) fn array<const N: usize>(v: Option<Vec<f64>>) -> Option<[f64; N]> {
    v.and_then(|v| <[f64; N]>::try_from(v.get(..N)?).ok())
}
