//! The GPU mirror fed by a real server: a `naadf serve` process, a mirror client following
//! its stream, and a [`GpuWorld`] synced with `write_buffer` after every message. The
//! device copy, read back, must equal the mirror's buffers and give the server's digest
//! (Mesa lavapipe in CI).

mod support;

use naadf_client::gpu::{Gpu, GpuWorld};
use naadf_client::{Client, Ended, Error, Pose, Spawn};
use std::ops::ControlFlow;
use std::time::Duration;
use support::{random_op, serve_world, start_world};

/// Voxel edits sent by the editor; with the model, the spawn and the moves below the
/// server ends at version `EDITS + 4`.
const EDITS: u64 = 36;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn gpu_world_synced_from_a_server_stream_equals_the_mirror() {
    let gpu = match Gpu::new() {
        Ok(g) => g,
        Err(e) => {
            eprintln!("skipping the GPU mirror test: {e}");
            return;
        }
    };
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);

    let viewer = Client::connect(&server.url, Some("viewer"), None).await.unwrap();
    let mut session = viewer.join(None).await.unwrap();

    // Voxel edits of every kind, then entities: a model, a spawn at odd rotations and
    // moves, so that every GPU buffer changes and grows while the viewer follows.
    let url = server.url.clone();
    let editor = tokio::spawn(async move {
        let c = Client::connect(&url, Some("editor"), None).await.unwrap();
        let mut rng = 17;
        for seq in 1..=EDITS {
            c.edit(random_op(&mut rng), seq).await.unwrap();
        }
        let model = r#"{"op":"define_model","name":"crate","size":[5,3,4],"voxels":[[0,0,0,2],[4,2,3,3],[2,1,1,4]]}"#;
        c.edit(model, EDITS + 1).await.unwrap();
        let rot = [0.1, 0.38268343236508984, -0.2, 0.8958];
        let entities: Vec<Spawn> = (1..=24)
            .map(|id| Spawn {
                model: "crate".into(),
                pose: Pose {
                    id,
                    pos: [5.0 * f64::from(id), 40.0, 3.5 * f64::from(id)],
                    rot,
                },
            })
            .collect();
        c.spawn_entities(&entities, EDITS + 2).await.unwrap();
        for k in 0..2u32 {
            let moves: Vec<Pose> = (1..=24)
                .step_by(2 + k as usize)
                .map(|id| Pose {
                    id,
                    pos: [100.25 - 3.0 * f64::from(id), 45.5, 7.0 + f64::from(k * id)],
                    rot,
                })
                .collect();
            c.move_entities(&moves, EDITS + 3 + u64::from(k)).await.unwrap();
        }
    });

    let last = EDITS + 4;
    let mut gpu_world: Option<GpuWorld> = None;
    let (mut syncs, mut checks, mut reallocations) = (0u32, 0u32, 0u32);
    let ended = session
        .follow(
            tokio::time::sleep(Duration::from_secs(300)),
            |m| -> Result<ControlFlow<()>, Error> {
                let Some(w) = m.world().filter(|_| m.is_live()) else {
                    return Ok(ControlFlow::Continue(()));
                };
                match &mut gpu_world {
                    // Parts of one 64 KiB page: the larger buffers span several bindings.
                    None => gpu_world = Some(GpuWorld::with_part_words(&gpu, w, 16 * 1024).unwrap()),
                    Some(g) => {
                        let up = g.sync(w).unwrap();
                        reallocations += u32::from(up.reallocated);
                        syncs += 1;
                    }
                }
                // Read back now and then while the stream runs, not only at the end.
                if syncs % 8 == 1 {
                    let g = gpu_world.as_ref().unwrap();
                    assert_eq!(g.first_difference(&gpu, w).unwrap(), None, "at version {}", w.version());
                    checks += 1;
                }
                let done = w.version() == last && m.is_quiescent();
                Ok(if done {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                })
            },
        )
        .await
        .unwrap();
    assert_eq!(ended, Ended::Done, "the stream ended before version {last}");
    editor.await.unwrap();

    let w = session.mirror().world().unwrap();
    let g = gpu_world.unwrap();
    assert_eq!(g.first_difference(&gpu, w).unwrap(), None);
    assert_eq!(g.digest(&gpu, w).unwrap(), w.digest(), "the device copy's digest");
    assert_eq!(w.entity_table().instances.len(), 24, "every entity reached the mirror");
    eprintln!(
        "{syncs} syncs ({reallocations} with reallocation), {checks} intermediate read-backs, version {}",
        w.version()
    );
    assert!(syncs as u64 >= last, "one sync per delta at least");
    server.stop();
}
