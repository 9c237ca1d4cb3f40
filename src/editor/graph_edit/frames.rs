//! Frames (Blender's Frame node): a labelled, coloured box the editor draws behind a set of
//! nodes. A frame is layout only; these are its edits: set one (create, relabel, recolour,
//! delete), join nodes in a new frame (Ctrl+J), take nodes out of their frames (Alt+P).
//! A node is in at most one frame, and a frame holds at least one node.

use super::GraphEdit;
use crate::material::{Frame, Graph};

/// The colour a new frame gets (linear RGB): a dim slate that keeps nodes readable on it.
pub const DEFAULT_FRAME_COLOR: [f32; 3] = [0.22, 0.25, 0.32];

/// Applies [`GraphEdit::SetFrame`].
pub(super) fn set_frame(
    graph: &mut Graph,
    id: String,
    frame: Option<Frame>,
) -> Result<GraphEdit, String> {
    if id.is_empty() {
        return Err("a frame needs an id".into());
    }
    let frame = match frame {
        Some(mut frame) => {
            frame.nodes.sort();
            frame.nodes.dedup();
            if frame.nodes.is_empty() {
                return Err(format!("frame \"{id}\" must hold at least one node"));
            }
            if let Some(missing) = frame.nodes.iter().find(|n| !graph.nodes.contains_key(*n)) {
                return Err(format!("frame \"{id}\": no node \"{missing}\""));
            }
            if !frame.color.iter().all(|c| (0.0..=1.0).contains(c)) {
                return Err(format!(
                    "frame \"{id}\": colour channels must be in [0, 1], not {:?}",
                    frame.color
                ));
            }
            let other = graph
                .frames
                .iter()
                .filter(|(other, _)| **other != id)
                .find_map(|(other, f)| {
                    let node = frame.nodes.iter().find(|n| f.nodes.contains(n))?;
                    Some((other, node))
                });
            if let Some((other, node)) = other {
                return Err(format!(
                    "node \"{node}\" is already in frame \"{other}\" (a node is in one frame)"
                ));
            }
            Some(frame)
        }
        None => None,
    };
    let old = match frame {
        Some(frame) => graph.frames.insert(id.clone(), frame),
        None => match graph.frames.remove(&id) {
            Some(old) => Some(old),
            None => return Err(format!("no frame \"{id}\"")),
        },
    };
    Ok(GraphEdit::SetFrame { id, frame: old })
}

/// An id for a new frame not used in `graph`.
pub(super) fn fresh_frame_id(graph: &Graph) -> String {
    std::iter::once("frame".to_owned())
        .chain((2..).map(|n| format!("frame_{n}")))
        .find(|id| !graph.frames.contains_key(id))
        .expect("a free id exists")
}

/// The edits that take nodes `ids` out of the frames holding them (a frame left empty
/// goes), or none when no frame holds any.
fn leave_frames(graph: &Graph, ids: &[String]) -> Vec<GraphEdit> {
    graph
        .frames
        .iter()
        .filter(|(_, f)| f.nodes.iter().any(|n| ids.contains(n)))
        .map(|(id, f)| {
            let mut kept = f.clone();
            kept.nodes.retain(|n| !ids.contains(n));
            GraphEdit::SetFrame {
                id: id.clone(),
                frame: (!kept.nodes.is_empty()).then_some(kept),
            }
        })
        .collect()
}

/// Ctrl+J: the edit that puts nodes `ids` of `graph` in a new frame (taking them out of
/// the frames they were in), and the new frame's id; `None` when no id is a node.
pub fn join_in_frame(graph: &Graph, ids: &[String]) -> Option<(GraphEdit, String)> {
    let nodes: Vec<String> = ids
        .iter()
        .filter(|id| graph.nodes.contains_key(*id))
        .cloned()
        .collect();
    if nodes.is_empty() {
        return None;
    }
    let id = fresh_frame_id(graph);
    let mut edits = leave_frames(graph, &nodes);
    edits.push(GraphEdit::SetFrame {
        id: id.clone(),
        frame: Some(Frame {
            label: "Frame".into(),
            color: DEFAULT_FRAME_COLOR,
            nodes,
        }),
    });
    Some((GraphEdit::Batch(edits), id))
}

/// Alt+P: the edit that takes nodes `ids` out of their frames; `None` when none is in one.
pub fn remove_from_frames(graph: &Graph, ids: &[String]) -> Option<GraphEdit> {
    let edits = leave_frames(graph, ids);
    (!edits.is_empty()).then_some(GraphEdit::Batch(edits))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Node;

    fn three_nodes() -> Graph {
        let mut g = Graph::default();
        for id in ["a", "b", "c"] {
            g.add(id, Node::new("noise_texture"));
        }
        g
    }

    #[test]
    fn joining_moves_nodes_between_frames_and_every_step_reverts() {
        let start = three_nodes();
        let mut g = start.clone();
        let (join, first) = join_in_frame(&g, &["a".into(), "b".into()]).unwrap();
        let undo_first = join.apply(&mut g).unwrap();
        assert_eq!(g.frames[&first].nodes, ["a", "b"]);
        let after_first = g.clone();
        // b moves to a new frame: it leaves the first.
        let (join, second) = join_in_frame(&g, &["b".into(), "c".into()]).unwrap();
        let undo_second = join.apply(&mut g).unwrap();
        assert_eq!(g.frames[&first].nodes, ["a"]);
        assert_eq!(g.frames[&second].nodes, ["b", "c"]);
        // Alt+P on a: its frame, left empty, goes.
        let undo_leave = remove_from_frames(&g, &["a".into()])
            .unwrap()
            .apply(&mut g)
            .unwrap();
        assert!(!g.frames.contains_key(&first));
        // Deleting c keeps the frame of b.
        let undo_remove = GraphEdit::RemoveNode { id: "c".into() }
            .apply(&mut g)
            .unwrap();
        assert_eq!(g.frames[&second].nodes, ["b"]);
        for undo in [undo_remove, undo_leave, undo_second] {
            undo.apply(&mut g).unwrap();
        }
        assert_eq!(g, after_first);
        undo_first.apply(&mut g).unwrap();
        assert_eq!(g, start);
    }

    #[test]
    fn a_frame_of_missing_or_shared_nodes_is_refused() {
        let mut g = three_nodes();
        let frame = |nodes: &[&str]| Frame {
            label: "F".into(),
            color: [0.5; 3],
            nodes: nodes.iter().map(|n| n.to_string()).collect(),
        };
        let e = set_frame(&mut g, "f".into(), Some(frame(&["zz"]))).unwrap_err();
        assert!(e.contains("zz"), "{e}");
        set_frame(&mut g, "f".into(), Some(frame(&["a"]))).unwrap();
        let e = set_frame(&mut g, "g".into(), Some(frame(&["a", "b"]))).unwrap_err();
        assert!(e.contains("\"a\"") && e.contains("\"f\""), "{e}");
        let e = set_frame(&mut g, "g".into(), Some(frame(&[]))).unwrap_err();
        assert!(e.contains("at least one"), "{e}");
        assert_eq!(g.frames.len(), 1);
    }
}
