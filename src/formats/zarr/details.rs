//! What `info` shows of an OME-Zarr store: the image read, its axes, levels, chunking, codecs
//! and labels, every name the store's metadata gives escaped by the one rule (`names::text`).

use serde_json::Value;

use super::ZarrInfo;
use crate::error::names::text;
use crate::formats::details::{Details, json_of};

impl Details for ZarrInfo {
    fn format_words(&self) -> Option<String> {
        Some(match &self.version {
            Some(version) => format!("OME-Zarr {version} on Zarr v{}", self.zarr_format),
            None => format!("a plain Zarr v{} array", self.zarr_format),
        })
    }

    fn lines(&self) -> Vec<(String, String)> {
        let shape = |s: &[u64]| s.iter().map(u64::to_string).collect::<Vec<_>>().join("x");
        let list = |names: &[String]| names.iter().map(|n| text(n)).collect::<Vec<_>>().join(", ");
        let mut lines = Vec::new();
        let mut line = |label: &str, value: String| lines.push((label.to_string(), value));
        if !self.image.is_empty() {
            line("image", text(&self.image));
        }
        let axes: Vec<String> = self
            .axes
            .iter()
            .map(|a| match &a.unit {
                Some(unit) => format!("{} ({}, {})", text(&a.name), text(&a.kind), text(unit)),
                None => format!("{} ({})", text(&a.name), text(&a.kind)),
            })
            .collect();
        line("axes", axes.join(", "));
        let levels: Vec<String> = self
            .levels
            .iter()
            .map(|l| {
                let path = if l.path.is_empty() {
                    ".".into()
                } else {
                    text(&l.path)
                };
                match l.pyramid_level {
                    Some(k) => format!("{path} {} (pyramid level {k})", shape(&l.shape)),
                    None => format!("{path} {} (not on the pyramid's grid)", shape(&l.shape)),
                }
            })
            .collect();
        line("levels", levels.join(", "));
        line(
            "chunks",
            match &self.inner_chunks {
                Some(inner) => format!("{} in shards of {}", shape(inner), shape(&self.chunks)),
                None => shape(&self.chunks),
            },
        );
        let codecs = if self.codecs.is_empty() {
            "none".to_string()
        } else {
            list(&self.codecs)
        };
        line("codecs", format!("{codecs} ({})", text(&self.data_type)));
        if !self.labels.is_empty() {
            line(
                "labels",
                format!("{}  (--label-image NAME reads one)", list(&self.labels)),
            );
        }
        lines
    }

    fn json(&self) -> Value {
        json_of(self)
    }
}
