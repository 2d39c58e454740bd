//! Inputs the fuzz targets (`fuzz/`, see RELIABILITY.md) found, kept as regression tests.
//! Each names the target and what the input broke.

use naadf_world::ops::Batch;

/// Ops lines (target `ops`) whose `define_material` numbers are finite JSON but overflow
/// `f32`, so that the parsed material holds an infinity. Found by the ops fuzz target: the
/// canonical line of such a batch wrote `null` for the infinity and did not parse back.
const OVERFLOWING_F32: [&str; 4] = [
    r#"{"op":"define_material","id":811,"kind":"metal","albedo":[1,0.5,1e65],"roughness":0.2}"#,
    r#"{"op":"define_material","id":300,"kind":"metal","albedo":[12222222222222222222222222222222222222222222222222220.5,1,25],"roughness":0.2}"#,
    r#"{"op":"define_material","id":900,"kind":"metal","albedo":[1,0,4.1e95],"roughness":0.2}"#,
    r#"{"op":"define_material","id":411,"kind":"metal","albedo":[0,0,4.1e55],"roughness":0.2}"#,
];

/// The parser itself refuses a number that does not fit the field's type, as it does for
/// integer fields, instead of handing on an infinity whose canonical line does not parse.
#[test]
fn fuzz_ops_overflowing_f32_is_refused_by_the_parser() {
    for line in OVERFLOWING_F32 {
        let e = Batch::parse_line(line).unwrap_err().to_string();
        assert!(e.contains("does not fit a 32-bit float"), "{line}: {e}");
    }
    // In range, the same op parses and its canonical line parses back to it.
    let fine = r#"{"op":"define_material","id":811,"kind":"metal","albedo":[1,0.5,0.25],"roughness":0.2}"#;
    let batch = Batch::parse_line(fine).unwrap();
    assert_eq!(Batch::parse_line(&batch.to_json_line()).unwrap(), batch);
}
