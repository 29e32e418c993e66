//! Cycles: pass-level dependency cycles, checked once every reference resolves.

use petgraph::graph::{DiGraph, NodeIndex};

use super::{Checker, Ref};

impl Checker<'_> {
    /// Pass-level dependency cycles (carried feedback and history are not cycles).
    pub(super) fn check_cycles(&mut self) {
        let mut g: DiGraph<usize, ()> = DiGraph::new();
        let nodes: Vec<NodeIndex> = (0..self.passes.len()).map(|i| g.add_node(i)).collect();
        let producers_of = |r: &Ref, out: &mut Vec<usize>| match r {
            Ref::Output { pass, .. } => out.push(*pass),
            Ref::Carry { group, name } => {
                if let Some((Ref::Output { pass, .. }, _)) = self.groups[*group].carry.get(name) {
                    out.push(*pass);
                }
            }
            _ => {}
        };
        let mut edges = Vec::new();
        for (pi, p) in self.passes.iter().enumerate() {
            let mut producers = Vec::new();
            for r in p.inputs.values().chain(p.otherwise.values()) {
                producers_of(r, &mut producers);
            }
            for q in producers {
                edges.push((q, pi));
            }
        }
        for (a, b) in edges {
            g.add_edge(nodes[a], nodes[b], ());
        }
        let sccs = petgraph::algo::tarjan_scc(&g);
        for scc in sccs {
            let is_cycle = scc.len() > 1 || g.contains_edge(scc[0], scc[0]);
            if !is_cycle {
                continue;
            }
            // Walk the cycle from its first-declared pass.
            let start = *scc.iter().min_by_key(|n| g[**n]).unwrap_or(&scc[0]);
            let mut path = vec![start];
            let mut cur = start;
            loop {
                let next = g
                    .neighbors(cur)
                    .filter(|n| scc.contains(n))
                    .min_by_key(|n| if *n == start { 0 } else { 1 + g[*n] });
                match next {
                    Some(n) if n == start || path.contains(&n) => {
                        path.push(n);
                        break;
                    }
                    Some(n) => {
                        path.push(n);
                        cur = n;
                    }
                    None => break,
                }
            }
            let names: Vec<&str> = path.iter().map(|n| self.passes[g[*n]].id.as_str()).collect();
            let first = &self.passes[g[start]];
            self.err(
                self.loc.pass_field(first.path, &first.id, "inputs"),
                format!("the passes form a cycle: {}", names.join(" → ")),
                Some(
                    "break the cycle; feed values back across iterations with a Repeat group's carry, or across frames with history"
                        .to_string(),
                ),
            );
        }
    }
}
