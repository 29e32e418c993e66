//! Pooling: WebGPU has no memory aliasing, so reuse by descriptor is the equivalent. A target's
//! lifetime runs from the step that writes it to the last step that reads it (a Modify chain —
//! blending into an accumulation target, a depth buffer tested and rewritten — is one texture
//! from its first write to its last read). Targets are assigned first-fit, in order of first
//! write, to a slot of the same format and size whose previous holder was last read strictly
//! before. A chain of N passes each reading the previous output therefore needs 2 slots, and a
//! repeat group's feedback ping-pongs between two.

use std::collections::BTreeMap;

use crate::plan::{Resource, ResourceId, Slot};

pub(super) fn root_of(resources: &[Resource], mut id: ResourceId) -> ResourceId {
    while let Some(prev) = resources[id].modifies {
        id = prev;
    }
    id
}

/// 7. Pool targets over chain lifetimes.
pub(super) fn pool(resources: &mut [Resource], persistent_roots: &[ResourceId]) -> Vec<Slot> {
    // Chain roots in one forward pass (a Modify output is always created after the version it
    // modifies), so a repeat group's carried chain of N versions costs O(N), not O(N²).
    let mut roots: Vec<ResourceId> = Vec::with_capacity(resources.len());
    for id in 0..resources.len() {
        let root = match resources[id].modifies {
            Some(prev) if prev < id => roots[prev],
            Some(prev) => root_of(resources, prev),
            None => id,
        };
        roots.push(root);
    }
    let persistent: std::collections::BTreeSet<ResourceId> = persistent_roots.iter().copied().collect();
    // Chain lifetimes, keyed by root.
    let mut chains: BTreeMap<ResourceId, (usize, usize, Vec<ResourceId>)> = BTreeMap::new();
    for id in 0..resources.len() {
        if resources[id].desc.slot_desc().is_none() {
            continue;
        }
        let root = roots[id];
        let e = chains.entry(root).or_insert((resources[root].producer, 0, Vec::new()));
        e.1 = e.1.max(resources[id].last_use);
        e.2.push(id);
    }
    let mut by_start: Vec<(ResourceId, usize, usize, Vec<ResourceId>)> =
        chains.into_iter().map(|(root, (start, end, members))| (root, start, end, members)).collect();
    by_start.sort_by_key(|(root, start, _, _)| (*start, *root));
    let mut slots: Vec<Slot> = Vec::new();
    let mut busy_until: Vec<usize> = Vec::new();
    for (root, start, end, members) in by_start {
        let Some(desc) = resources[root].desc.slot_desc() else { continue };
        let persistent = persistent.contains(&root);
        let reuse = if persistent {
            None
        } else {
            (0..slots.len()).find(|&s| !slots[s].persistent && slots[s].desc == desc && busy_until[s] < start)
        };
        let s = match reuse {
            Some(s) => s,
            None => {
                slots.push(Slot { desc, persistent, holds: Vec::new() });
                busy_until.push(0);
                slots.len() - 1
            }
        };
        busy_until[s] = end;
        for m in members {
            resources[m].slot = Some(s);
            slots[s].holds.push(m);
        }
    }
    slots
}
