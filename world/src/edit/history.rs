//! Per-user undo and redo histories, and the table of answered client sequence numbers
//! that makes retried requests idempotent. The server keeps them in the state its
//! snapshots persist and rebuilds them when it replays its log; an in-process replay
//! keeps them the same way, so both undo exactly alike.

use super::UndoRecord;
use crate::ops::Batch;
use crate::world::World;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, VecDeque};

/// Most undo steps kept per user.
pub const MAX_UNDO: usize = 64;
/// Most undone voxels kept per user across its history (older steps are dropped first).
pub const MAX_UNDO_VOXELS: usize = 1 << 22;
/// Most answered client sequence numbers remembered per user.
pub const MAX_SEQS: usize = 4096;

/// What kind of request an applied batch came from, which decides where its undo record
/// goes: a new edit pushes it on the undo stack (and clears redo), an undo moves one step
/// from undo to redo, a redo moves one back. Logs record it with each batch so that a
/// replay rebuilds the same histories.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum BatchKind {
    /// An edit or entity request.
    Edit,
    /// An undo of the user's latest edit.
    Undo,
    /// A redo of the user's latest undo.
    Redo,
}

/// One user's history.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
struct UserHistory {
    undo: VecDeque<UndoRecord>,
    redo: Vec<UndoRecord>,
    seqs: BTreeMap<u64, u64>,
}

impl UserHistory {
    fn trim(&mut self) {
        let mut voxels: usize = self.undo.iter().map(|r| r.voxels.len()).sum();
        while self.undo.len() > MAX_UNDO || (voxels > MAX_UNDO_VOXELS && self.undo.len() > 1) {
            let r = self.undo.pop_front().expect("non-empty");
            voxels -= r.voxels.len();
        }
    }
}

/// Every user's history and answered sequence numbers.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Histories {
    users: BTreeMap<String, UserHistory>,
}

impl Histories {
    /// The version an earlier request `(user, client_seq)` produced, if it was answered.
    pub fn answered(&self, user: &str, client_seq: u64) -> Option<u64> {
        if client_seq == 0 {
            return None;
        }
        self.users.get(user)?.seqs.get(&client_seq).copied()
    }

    /// Remembers that `(user, client_seq)` produced `version` (sequence 0 is never kept).
    pub fn answer(&mut self, user: &str, client_seq: u64, version: u64) {
        if client_seq == 0 {
            return;
        }
        let seqs = &mut self.users.entry(user.to_owned()).or_default().seqs;
        seqs.insert(client_seq, version);
        while seqs.len() > MAX_SEQS {
            seqs.pop_first();
        }
    }

    /// The batch an undo (`redo` false) or redo of `user` applies to `world` now, with the
    /// kind to [`Histories::record`] it as, or why there is none.
    pub fn history_batch(&self, user: &str, redo: bool, world: &World) -> Result<(Batch, BatchKind), String> {
        let (record, kind, what) = if redo {
            (self.next_redo(user), BatchKind::Redo, "redo")
        } else {
            (self.next_undo(user), BatchKind::Undo, "undo")
        };
        record
            .map(|r| (r.undo_batch(world), kind))
            .ok_or_else(|| format!("user '{user}' has nothing to {what}"))
    }

    /// Records an applied batch of `kind`: its undo record goes on the right stack, and
    /// `(user, client_seq)` is answered with `version`.
    pub fn record(&mut self, user: &str, client_seq: u64, kind: BatchKind, version: u64, undo: UndoRecord) {
        match kind {
            BatchKind::Edit => self.edited(user, undo),
            BatchKind::Undo => self.undone(user, undo),
            BatchKind::Redo => self.redone(user, undo),
        }
        self.answer(user, client_seq, version);
    }

    /// Records a new edit's undo record; a new edit clears the user's redo stack.
    pub fn edited(&mut self, user: &str, undo: UndoRecord) {
        let h = self.users.entry(user.to_owned()).or_default();
        h.redo.clear();
        h.undo.push_back(undo);
        h.trim();
    }

    /// The record the user's next undo would apply.
    pub fn next_undo(&self, user: &str) -> Option<&UndoRecord> {
        self.users.get(user)?.undo.back()
    }

    /// The record the user's next redo would apply.
    pub fn next_redo(&self, user: &str) -> Option<&UndoRecord> {
        self.users.get(user)?.redo.last()
    }

    /// An undo was applied: its record moves off the undo stack, and the record that
    /// reverts the undo goes on the redo stack.
    pub fn undone(&mut self, user: &str, redo: UndoRecord) {
        let h = self.users.entry(user.to_owned()).or_default();
        h.undo.pop_back();
        h.redo.push(redo);
    }

    /// A redo was applied: its record moves off the redo stack, and the record that
    /// reverts the redo goes back on the undo stack.
    pub fn redone(&mut self, user: &str, undo: UndoRecord) {
        let h = self.users.entry(user.to_owned()).or_default();
        h.redo.pop();
        h.undo.push_back(undo);
        h.trim();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(n: u32) -> UndoRecord {
        UndoRecord {
            voxels: vec![([n, 0, 0], 0, 1)],
            entities: Vec::new(),
        }
    }

    #[test]
    fn stacks_and_sequence_numbers() {
        let mut h = Histories::default();
        h.edited("a", rec(1));
        h.edited("a", rec(2));
        assert_eq!(h.next_undo("a"), Some(&rec(2)));
        assert_eq!(h.next_undo("b"), None);
        h.undone("a", rec(20));
        assert_eq!(h.next_undo("a"), Some(&rec(1)));
        assert_eq!(h.next_redo("a"), Some(&rec(20)));
        h.redone("a", rec(2));
        assert_eq!(h.next_redo("a"), None);
        h.undone("a", rec(20));
        h.edited("a", rec(3));
        assert_eq!(h.next_redo("a"), None, "a new edit clears redo");
        for i in 0..(MAX_UNDO + 5) as u32 {
            h.edited("c", rec(i));
        }
        assert_eq!(h.users["c"].undo.len(), MAX_UNDO);

        h.answer("a", 7, 40);
        h.answer("a", 0, 41);
        assert_eq!(h.answered("a", 7), Some(40));
        assert_eq!(h.answered("a", 0), None);
        assert_eq!(h.answered("b", 7), None);
        for s in 1..=(MAX_SEQS as u64 + 10) {
            h.answer("d", s, s);
        }
        assert_eq!(h.answered("d", 1), None);
        assert_eq!(h.answered("d", MAX_SEQS as u64 + 10), Some(MAX_SEQS as u64 + 10));
    }
}
