//! Checkpoint layout versions (issue 13): the header carries a version that changes with the
//! layout, and a checkpoint of an older layout is refused with a message that says so.
mod common;

use std::path::Path;
use sylva::sim::checkpoint::{restore, to_bytes, LAYOUT_VERSION};
use sylva::sim::trees::N_CAUSES;
use sylva::sim::cohorts::N_REGEN_CAUSES;

fn world() -> (sylva::sim::Scenario, sylva::sim::World) {
    common::world(&common::ScenarioToml::new("ck", 5, 5).species(&["beech"]).uniform(4, 4, 20.0, 200.0).planted("beech", 3.0, 10.0).build())
}

#[test]
fn version_follows_the_cause_counts() {
    assert_eq!((LAYOUT_VERSION >> 8) & 0xff, N_CAUSES as u32);
    assert_eq!(LAYOUT_VERSION & 0xff, N_REGEN_CAUSES as u32);
    assert!(LAYOUT_VERSION >> 16 >= 5, "layouts up to SYLVACK3 came before versions; 5 added the length, identity and CRC-32");
}

#[test]
fn round_trip_and_old_layouts_refused_with_a_clear_message() {
    let (sc, mut w) = world();
    let rows = common::run(&sc, &mut w, 3);
    let bytes = to_bytes(&w, &rows);
    assert_eq!(&bytes[..8], b"SYLVACKV");
    assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()), LAYOUT_VERSION);
    let p = Path::new("run/checkpoint.bin");
    let (_, mut fresh) = world();
    assert_eq!(restore(&mut fresh, &bytes, p).unwrap(), rows);
    assert_eq!(fresh.stand.trees, w.stand.trees);
    assert_eq!(fresh.stand.year, 3);

    // a file of the last layout before versions: "SYLVACK3" then the body
    let mut old = b"SYLVACK3".to_vec();
    old.extend_from_slice(&bytes[12..]);
    let e = restore(&mut world().1, &old, p).unwrap_err().to_string();
    assert!(e.starts_with("run/checkpoint.bin: ") && e.contains("older Sylva") && e.contains("SYLVACK3") && e.contains("without --resume"), "{e}");

    // another layout version (e.g. a build with one more death cause)
    let mut other = bytes.clone();
    other[8..12].copy_from_slice(&(LAYOUT_VERSION + 256).to_le_bytes());
    let e = restore(&mut world().1, &other, p).unwrap_err().to_string();
    assert!(e.contains(&format!("layout version {}.{}.{}", LAYOUT_VERSION >> 16, N_CAUSES + 1, N_REGEN_CAUSES)) && e.contains("differs from this build's") && e.contains("without --resume"), "{e}");

    let e = restore(&mut world().1, b"PK\x03\x04 not a checkpoint", p).unwrap_err().to_string();
    assert!(e.contains("not a Sylva checkpoint"), "{e}");
    let e = restore(&mut world().1, &bytes[..10], p).unwrap_err().to_string();
    assert!(e.contains("truncated"), "{e}");
}

/// Checkpoints are zstd-compressed (layout base 7, issue 34). Since layout 10 (round 42) the
/// stand table's rows hold the per-species rows and year 0: a checkpoint of an older layout (the
/// uncompressed 6, the compressed 7) is refused, naming its version, not misread.
#[test]
fn compressed_checkpoints_read_and_the_layouts_before_refused_naming_their_version() {
    let (sc, mut w) = world();
    let rows = common::run(&sc, &mut w, 3);
    let bytes = to_bytes(&w, &rows);
    assert_eq!(LAYOUT_VERSION >> 16, 14);
    assert!(rows.iter().all(|r| r.species.len() == w.site.pool.len()), "every row holds its per-species rows");
    // the identity and body: one zstd frame between the file length and the checksum
    let plain_body = zstd::stream::decode_all(&bytes[20..bytes.len() - 4]).unwrap();
    assert!(plain_body.len() > bytes.len(), "compressed {} B, body {} B", bytes.len(), plain_body.len());
    let p = Path::new("run/checkpoint.bin");
    let (_, mut fresh) = world();
    assert_eq!(restore(&mut fresh, &bytes, p).unwrap(), rows);
    assert_eq!(fresh.stand.trees, w.stand.trees);
    assert_eq!(fresh.stand.cohorts, w.stand.cohorts);
    // the layouts before: uncompressed 6, compressed 7, and 10 (round 42; round 44's 12 adds the
    // drought index, each species' top height over its own area and the cohorts' stress years;
    // round 45's 14 the fine seed grids of the two-scale dispersal kernel)
    for (base, body) in [(6u32, &plain_body[..]), (7, &bytes[20..bytes.len() - 4]), (10, &bytes[20..bytes.len() - 4]), (12, &bytes[20..bytes.len() - 4])] {
        let mut old = b"SYLVACKV".to_vec();
        old.extend_from_slice(&(base << 16 | (LAYOUT_VERSION & 0xffff)).to_le_bytes());
        old.extend_from_slice(&[0; 8]);
        old.extend_from_slice(body);
        old.extend_from_slice(&[0; 4]);
        sylva::sim::checkpoint::reseal(&mut old);
        let e = restore(&mut world().1, &old, p).unwrap_err().to_string();
        assert!(e.starts_with("run/checkpoint.bin: ") && e.contains(&format!("layout version {base}.")) && e.contains("differs from this build's 14.") && e.contains("without --resume"), "{e}");
    }
    // a frame that does not decode, sealed with a matching checksum, is refused by name
    let mut bad = bytes.clone();
    let mid = 20 + (bytes.len() - 24) / 2;
    bad[mid..mid + 8].copy_from_slice(&[0xff; 8]);
    sylva::sim::checkpoint::reseal(&mut bad);
    let e = restore(&mut world().1, &bad, p).unwrap_err().to_string();
    assert!(e.starts_with("run/checkpoint.bin: ") && e.contains("corrupt"), "{e}");
}
