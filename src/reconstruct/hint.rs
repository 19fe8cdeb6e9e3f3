//! A spade hint generator whose hint is set explicitly by the caller, per thread.
//!
//! spade's nearest-neighbour query and its insertion locate their point through the
//! triangulation's hint generator and offer no `_with_hint` variant. The stock
//! generators are either shared between threads (`LastUsedVertexHintGenerator`: the
//! walk, and so the answer among equidistant neighbours, would depend on thread
//! scheduling) or pay a hierarchy descent per query. This one returns whatever the
//! current thread last stored with [`ScanlineHint::set`]; the reconstruction stores the
//! previous pixel's vertex (or a ghost's source sample), which keeps every walk short
//! and a pure function of the row being processed.

use spade::handles::FixedVertexHandle;
use spade::{HasPosition, HintGenerator, Point2, Triangulation};
use std::cell::Cell;

thread_local! {
    static HINT: Cell<usize> = const { Cell::new(0) };
}

/// Zero-sized: the state lives in a thread-local, so the triangulation stays `Sync`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ScanlineHint;

impl ScanlineHint {
    /// Sets the start vertex of this thread's next walk.
    pub(crate) fn set(v: FixedVertexHandle) {
        HINT.with(|h| h.set(v.index()));
    }
}

impl HintGenerator<f64> for ScanlineHint {
    fn get_hint(&self, _position: Point2<f64>) -> FixedVertexHandle {
        // spade validates the handle, so a stale index (from another triangulation on
        // this thread) only costs a longer walk.
        FixedVertexHandle::from_index(HINT.with(Cell::get))
    }

    /// Lookups do not move the hint: the caller decides where the next walk starts.
    fn notify_vertex_lookup(&self, _vertex: FixedVertexHandle) {}

    fn notify_vertex_inserted(&mut self, vertex: FixedVertexHandle, _position: Point2<f64>) {
        Self::set(vertex);
    }

    fn notify_vertex_removed(
        &mut self,
        _swapped_in_point: Option<Point2<f64>>,
        _vertex: FixedVertexHandle,
        _vertex_position: Point2<f64>,
    ) {
        Self::set(FixedVertexHandle::from_index(0));
    }

    fn initialize_from_triangulation<TR, V>(_triangulation: &TR) -> Self
    where
        TR: Triangulation<Vertex = V>,
        V: HasPosition<Scalar = f64>,
    {
        Self
    }
}
