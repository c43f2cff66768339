//! What `info` shows of a VTK XML image data file: its arrays, point data then cell data, the one
//! read first.

use roxmltree::{Node, NodeId};
use serde::Serialize;

use crate::formats::details::{Details, json_of};

/// The most arrays listed.
const MAX_LISTED: usize = 256;

/// What `info` shows of a `.vti` file: its arrays, the one read first.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub(crate) struct VtiDetails {
    /// The arrays: the one read, then the others in the file's order.
    pub arrays: Vec<VtiArray>,
}

/// One `<DataArray>` of a `.vti` file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub(crate) struct VtiArray {
    /// Its `Name` as written.
    pub name: String,
    /// Its `type` as written (`UInt8` … `Float64`).
    #[serde(rename = "type")]
    pub ty: String,
    /// Its `NumberOfComponents` (1 when none is written; 0 when it is not a number).
    pub components: u64,
    /// `point` or `cell` data.
    pub data: &'static str,
}

impl Details for VtiDetails {
    fn lines(&self) -> Vec<(String, String)> {
        let arrays: Vec<String> = self
            .arrays
            .iter()
            .map(|a| {
                let name = crate::error::names::text(&a.name);
                let ty = crate::error::names::text(&a.ty);
                let times = match a.components {
                    1 => String::new(),
                    n => format!(" x{n}"),
                };
                format!("{name} ({ty}{times}, {} data)", a.data)
            })
            .collect();
        vec![("arrays".into(), arrays.join(", "))]
    }

    fn json(&self) -> serde_json::Value {
        json_of(self)
    }
}

/// The arrays of the `<Piece>` `piece`, the one at `read` first.
pub(super) fn arrays(piece: Node, read: NodeId) -> VtiDetails {
    let mut arrays = Vec::new();
    let mut first = None;
    for (section, data) in [("PointData", "point"), ("CellData", "cell")] {
        let nodes = piece
            .children()
            .filter(|n| n.has_tag_name(section))
            .flat_map(|s| s.children().filter(|n| n.has_tag_name("DataArray")));
        for node in nodes.take(MAX_LISTED) {
            if node.id() == read {
                first = Some(arrays.len());
            }
            arrays.push(VtiArray {
                name: node.attribute("Name").unwrap_or("").to_string(),
                ty: node.attribute("type").unwrap_or("").to_string(),
                components: node
                    .attribute("NumberOfComponents")
                    .map_or(Some(1), |c| c.trim().parse().ok())
                    .unwrap_or(0),
                data,
            });
        }
    }
    if let Some(i) = first {
        let read = arrays.remove(i);
        arrays.insert(0, read);
    }
    arrays.truncate(MAX_LISTED);
    VtiDetails { arrays }
}
