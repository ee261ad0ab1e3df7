//! Traversal from a viewpoint (seed 000's `DisplayBSP`, with an explicit stack): far
//! subtree, node, near subtree for back to front, the reverse for front to back.

use std::ops::ControlFlow;

use super::{BspTraversal, BspTree, BspVisitor, Viewpoint};

impl BspTree {
    /// Visits the fragments in back-to-front or front-to-back order from a viewpoint
    /// (seed 000's `DisplayBSP`, with an explicit stack). The visitor may stop the
    /// traversal by returning `ControlFlow::Break`; returns whether it ran to the end.
    ///
    /// A viewpoint exactly on a node's plane sees that node's fragments edge-on and
    /// the two subtrees on opposite sides of a line of the image, so either order is
    /// correct there; the front subtree is taken as the near one.
    pub fn traverse<F>(&self, viewpoint: Viewpoint, traversal: BspTraversal, visit: F) -> bool
    where
        F: FnMut(u32) -> ControlFlow<()>,
    {
        struct Fragments<F>(F);
        impl<F: FnMut(u32) -> ControlFlow<()>> BspVisitor for Fragments<F> {
            fn fragment(&mut self, fragment: u32) -> ControlFlow<()> {
                (self.0)(fragment)
            }
        }
        self.traverse_with(viewpoint, traversal, &mut Fragments(visit))
    }

    /// [`BspTree::traverse`] with a visitor that may also skip whole subtrees
    /// ([`BspVisitor::enter`]).
    pub fn traverse_with<V: BspVisitor>(
        &self,
        viewpoint: Viewpoint,
        traversal: BspTraversal,
        visitor: &mut V,
    ) -> bool {
        enum Item {
            Node(u32),
            Fragments(u32),
        }
        let Some(root) = self.root() else {
            return true;
        };
        let viewpoint = viewpoint.relative_to(self.origin);
        let mut stack = vec![Item::Node(root)];
        while let Some(item) = stack.pop() {
            match item {
                Item::Node(n) => {
                    if !visitor.enter(n) {
                        continue;
                    }
                    let node = &self.nodes[n as usize];
                    let (near, far) = if viewpoint.side(&node.plane) >= 0.0 {
                        (node.front, node.back)
                    } else {
                        (node.back, node.front)
                    };
                    let (first, last) = match traversal {
                        BspTraversal::BackToFront => (far, near),
                        BspTraversal::FrontToBack => (near, far),
                    };
                    // The stack pops in reverse: push what is visited last first.
                    if let Some(c) = last {
                        stack.push(Item::Node(c));
                    }
                    stack.push(Item::Fragments(n));
                    if let Some(c) = first {
                        stack.push(Item::Node(c));
                    }
                }
                Item::Fragments(n) => {
                    let frags = self.node_fragments(n);
                    let flow = match traversal {
                        BspTraversal::BackToFront => {
                            frags.iter().try_for_each(|&f| visitor.fragment(f))
                        }
                        BspTraversal::FrontToBack => {
                            frags.iter().rev().try_for_each(|&f| visitor.fragment(f))
                        }
                    };
                    if flow.is_break() {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// The fragments in the order a traversal visits them.
    #[must_use]
    pub fn paint_order(&self, viewpoint: Viewpoint, traversal: BspTraversal) -> Vec<u32> {
        let mut out = Vec::with_capacity(self.node_fragments.len());
        self.traverse(viewpoint, traversal, |f| {
            out.push(f);
            ControlFlow::Continue(())
        });
        out
    }
}
