//! The patch form of the world stream, followed by a mirror written here from the
//! protocol's description alone: it copies bytes and never runs the edit engine
//! (`World::apply_record`). Its buffers must hash to the server's digest after every
//! delta, through edits of every kind, growth steps, entities, undo and redo, and a relay
//! must send the very same patches as the server.

mod support;

use naadf_client::{Client, Pose};
use naadf_proto::PROTOCOL_VERSION;
use naadf_proto::v1::world_service_client::WorldServiceClient;
use naadf_proto::v1::{DeltaForm, Header, JoinRequest, Patch, Run, Runs, world_message};
use naadf_world::digest::{BufferId, Digest, PAGE_BYTES, digest_of};
use prost::Message;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;
use support::{Server, random_op, serve_world, start_world};

/// A mirror of the patch form: the world's eight buffers as bytes.
#[derive(Default)]
struct PatchMirror {
    buffers: Vec<Vec<u8>>,
    version: u64,
    growth_seq: u32,
    quiescent: bool,
    /// Every patch received, with the digest after it.
    patches: Vec<(Patch, u64)>,
}

impl PatchMirror {
    /// The runs of `patch`, from its zstd frame if it has one.
    fn runs(patch: &Patch) -> Vec<Run> {
        if patch.zstd.is_empty() {
            return patch.runs.clone();
        }
        let plain = zstd::decode_all(patch.zstd.as_slice()).unwrap();
        Runs::decode(plain.as_slice()).unwrap().runs
    }

    /// Applies a patch: lengths first, then the runs in order; checks the digest.
    fn apply(&mut self, patch: &Patch, digest: u64) {
        for l in &patch.lengths {
            self.buffers[l.buffer as usize].resize(l.bytes as usize, 0);
        }
        for run in Self::runs(patch) {
            let buffer = &mut self.buffers[run.buffer as usize];
            let at = run.offset as usize;
            assert!(
                at + run.bytes.len() <= buffer.len(),
                "a run past the end of buffer {}",
                run.buffer
            );
            buffer[at..at + run.bytes.len()].copy_from_slice(&run.bytes);
        }
        let mine = self.digest();
        assert_eq!(
            mine,
            Digest(digest),
            "after version {} step {}",
            patch.version,
            patch.growth_seq
        );
        (self.version, self.growth_seq, self.quiescent) = (patch.version, patch.growth_seq, patch.quiescent);
        self.patches.push((patch.clone(), digest));
    }

    /// The world digest of the buffers: the XOR of each buffer's page hashes.
    fn digest(&self) -> Digest {
        BufferId::WORLD
            .into_iter()
            .zip(&self.buffers)
            .fold(Digest(0), |d, (id, bytes)| d ^ digest_of(id, bytes))
    }
}

/// Follows `url` in the patch form until it is quiescent at `version` or later. The
/// snapshot's pages are written into the buffers as they come (a patch-form snapshot
/// carries all eight buffers, the entity buffers too); from then on only bytes are copied.
async fn follow_patches(url: &str, until: impl Fn(&PatchMirror) -> bool) -> PatchMirror {
    let channel = tonic::transport::Endpoint::from_shared(url.to_owned())
        .unwrap()
        .connect()
        .await
        .unwrap();
    let request = JoinRequest {
        protocol_version: PROTOCOL_VERSION,
        delta_form: DeltaForm::Patch.into(),
        ..Default::default()
    };
    let mut stream = WorldServiceClient::new(channel)
        .join(request)
        .await
        .unwrap()
        .into_inner();
    let mut mirror = PatchMirror::default();
    // The header of the snapshot being received, and the page messages still to come.
    let mut snapshot: Option<(Header, u32)> = None;
    let read = async {
        loop {
            // `until` may turn true while no message comes: look again every 100 ms.
            let Ok(next) = tokio::time::timeout(Duration::from_millis(100), stream.message()).await else {
                if snapshot.is_none() && !mirror.buffers.is_empty() && until(&mirror) {
                    return;
                }
                continue;
            };
            let m = next.unwrap().expect("the stream goes on");
            match m.kind.expect("a message") {
                world_message::Kind::Delta(d) => {
                    assert!(d.change.is_empty(), "the patch form carries no record");
                    mirror.apply(d.patch.as_ref().expect("a patch"), d.digest);
                }
                world_message::Kind::Header(h) => {
                    assert!(!h.resume, "this mirror announced nothing to resume");
                    // Buffers 0–5 always, the entity buffers when they are not empty.
                    let ids: Vec<u32> = h.buffers.iter().map(|b| b.buffer).collect();
                    assert!(ids.starts_with(&[0, 1, 2, 3, 4, 5]) && ids.len() <= 8, "{ids:?}");
                    mirror.buffers = vec![Vec::new(); 8];
                    for b in &h.buffers {
                        mirror.buffers[b.buffer as usize] = vec![0; b.bytes as usize];
                    }
                    snapshot = Some((h.clone(), h.pages));
                }
                world_message::Kind::Page(p) => {
                    let bytes = zstd::decode_all(p.zstd.as_slice()).unwrap();
                    let buffer = &mut mirror.buffers[p.buffer as usize];
                    let mut at = 0;
                    for k in p.indices {
                        let lo = k as usize * PAGE_BYTES;
                        let n = PAGE_BYTES.min(buffer.len() - lo);
                        buffer[lo..lo + n].copy_from_slice(&bytes[at..at + n]);
                        at += n;
                    }
                    assert_eq!(at, bytes.len(), "a page group holds exactly its pages");
                    snapshot.as_mut().expect("pages follow a header").1 -= 1;
                }
                _ => {}
            }
            if let Some((h, 0)) = &snapshot {
                assert_eq!(
                    mirror.digest(),
                    Digest(h.digest),
                    "the snapshot's pages give its digest"
                );
                (mirror.version, mirror.growth_seq, mirror.quiescent) = (h.version, h.growth_seq, h.quiescent);
                snapshot = None;
            }
            if snapshot.is_none() && !mirror.buffers.is_empty() && until(&mirror) {
                return;
            }
        }
    };
    tokio::time::timeout(Duration::from_secs(120), read)
        .await
        .expect("the patch mirror caught up");
    mirror
}

/// Edits of every kind: ops, a model and entities spawned, moved and despawned, undo and
/// redo, with growth steps in between.
async fn edit_everything(c: &Client) {
    let mut rng = 11;
    let mut seq = 0;
    let mut next = || {
        seq += 1;
        seq
    };
    for _ in 0..20 {
        c.edit(random_op(&mut rng), next()).await.unwrap();
    }
    let (model, spawns) = support::crates();
    c.edit(model, next()).await.unwrap();
    c.spawn_entities(&spawns, next()).await.unwrap();
    let moved = Pose {
        id: 2,
        pos: [70.5, 55.25, 90.0],
        rot: [0.0, 0.0, 0.0, 1.0],
    };
    c.move_entities(&[moved], next()).await.unwrap();
    c.despawn_entities(&[3], next()).await.unwrap();
    for _ in 0..5 {
        c.edit(random_op(&mut rng), next()).await.unwrap();
    }
    c.undo(next()).await.unwrap();
    c.undo(next()).await.unwrap();
    c.redo(next()).await.unwrap();
    c.edit(r#"{"op":"box","min":[0,0,0],"max":[127,20,127],"material":0}"#, next())
        .await
        .unwrap();
}

/// The patch mirror stays on the server's digest at every delta, ends on the server's
/// final state, and a relay's patches are the server's, byte for byte.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_mirror_of_patches_alone_follows_the_server_and_a_relay_sends_the_same_patches() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &["--rate", "100000"], &[]);
    let relay = Server::relay(&server.url, &[], &dir.path().join("relay.log"));
    let c = Client::connect(&server.url, Some("ed"), None).await.unwrap();
    // Both mirrors join before the edits, so that they see every patch, and follow until
    // they are quiescent at the last version.
    let last = Arc::new(AtomicU64::new(u64::MAX));
    let follow = |url: String| {
        let last = last.clone();
        tokio::spawn(async move {
            follow_patches(&url, move |m| m.quiescent && m.version >= last.load(Ordering::Relaxed)).await
        })
    };
    let from_server = follow(server.url.clone());
    let from_relay = follow(relay.url.clone());
    tokio::time::sleep(Duration::from_millis(500)).await;
    edit_everything(&c).await;
    let status = support::quiescent(&server.url).await;
    last.store(status.version, Ordering::Relaxed);
    let (from_server, from_relay) = (from_server.await.unwrap(), from_relay.await.unwrap());
    assert_eq!(from_server.digest(), status.digest);
    // A mirror that joins now takes the entity buffers from the snapshot's pages.
    for url in [&server.url, &relay.url] {
        let late = follow_patches(url, |m| m.quiescent && m.version >= status.version).await;
        assert_eq!(late.digest(), status.digest, "{url}");
        assert!(
            !late.buffers[BufferId::EntityInstances as usize].is_empty(),
            "entities remain"
        );
    }
    let growth = from_server.patches.iter().filter(|(p, _)| p.growth_seq > 0).count();
    let compressed = from_server.patches.iter().filter(|(p, _)| !p.zstd.is_empty()).count();
    eprintln!(
        "{} patches ({growth} growth steps, {compressed} compressed)",
        from_server.patches.len()
    );
    assert!(growth > 0, "growth steps were followed");
    assert!(compressed > 0, "some patches travel compressed");
    assert!(
        from_server.patches.iter().any(|(p, _)| !p.lengths.is_empty()),
        "some change grew a buffer"
    );
    // The relay passes on the same changes as the same patches.
    let encode =
        |m: &PatchMirror| -> Vec<(Vec<u8>, u64)> { m.patches.iter().map(|(p, d)| (p.encode_to_vec(), *d)).collect() };
    let (relayed, served) = (encode(&from_relay), encode(&from_server));
    let summary = |m: &PatchMirror, k: usize| {
        m.patches.get(k).map(|(p, _)| {
            let runs: Vec<(u32, u64, usize)> = PatchMirror::runs(p)
                .iter()
                .map(|r| (r.buffer, r.offset, r.bytes.len()))
                .collect();
            (p.version, p.growth_seq, p.quiescent, p.lengths.clone(), runs)
        })
    };
    if let Some(k) = (0..relayed.len().max(served.len())).find(|&k| relayed.get(k) != served.get(k)) {
        panic!(
            "patch {k} of {} / {} differs:\nrelay  {:?}\nserver {:?}",
            relayed.len(),
            served.len(),
            summary(&from_relay, k),
            summary(&from_server, k)
        );
    }
    relay.stop();
    server.stop();
}
