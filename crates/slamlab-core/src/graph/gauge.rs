//! Gauge check: is every part of the graph held in place?
//!
//! The cost `Σ eᵀ Ω e` of relative measurements does not change when the whole map
//! moves rigidly, so `H = Jᵀ Ω J` is singular unless a prior or a fixed vertex
//! pins each connected part. This check finds the parts that nothing pins before
//! any factorization fails on them.

use super::{PoseGraph, VertexId};

/// A connected part of the graph that no prior or fixed vertex holds.
#[derive(Clone, Debug, PartialEq)]
pub struct FreeComponent {
    /// Number of vertices in the part.
    pub size: usize,
    /// The first few vertex ids of the part (at most 5), smallest first.
    pub sample: Vec<VertexId>,
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// The connected components that no prior or fixed vertex anchors, and the total
/// number of components.
pub(crate) fn free_components(graph: &PoseGraph) -> (Vec<FreeComponent>, usize) {
    let n = graph.vertices().len();
    let mut parent: Vec<usize> = (0..n).collect();
    let mut anchored = vec![false; n];
    for (i, v) in graph.vertices().iter().enumerate() {
        anchored[i] = v.fixed;
    }
    for e in graph.edges() {
        match e.vertices() {
            (a, Some(b)) => {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                if ra != rb {
                    parent[ra] = rb;
                }
            }
            (a, None) => anchored[a] = true,
        }
    }
    let mut root_anchored = vec![false; n];
    for i in 0..n {
        let r = find(&mut parent, i);
        root_anchored[r] |= anchored[i];
    }
    let mut members: std::collections::BTreeMap<usize, Vec<VertexId>> = Default::default();
    let mut components = 0;
    for i in 0..n {
        let r = find(&mut parent, i);
        if r == i {
            components += 1;
        }
        if !root_anchored[r] {
            members.entry(r).or_default().push(graph.vertices()[i].id);
        }
    }
    let mut free: Vec<FreeComponent> = members
        .into_values()
        .map(|mut ids| {
            ids.sort_unstable();
            FreeComponent {
                size: ids.len(),
                sample: ids.into_iter().take(5).collect(),
            }
        })
        .collect();
    free.sort_by_key(|c| c.sample.first().copied());
    (free, components)
}
