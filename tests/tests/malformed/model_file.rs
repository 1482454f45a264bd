//! Model files: any bytes, and any change to a valid file's header, metadata or weights (with
//! the checksum made right again so the change reaches the later checks), give a model or an
//! error naming the section (magic, version, length, checksum, metadata, chain, a tensor).

use std::sync::OnceLock;

use decoder::model::{FileError, ModelError, ModelKind, TrainedModel};
use proptest::prelude::*;

use crate::model_bytes::{join, join_claiming, split, valid_file};
use crate::mutate::{arbitrary_bytes, mutated, seeded};

/// How a `Malformed` message may start: each names the part of the file it is about.
const MALFORMED_PLACES: &[&str] = &[
    "body too short for the metadata length",
    "metadata length",
    "metadata: ",
    "format name",
    "signal chain configuration: ",
    "header says",
    "weight data is",
    "training summary is for",
];

/// The valid ResDD and CNN files (the CNN has the most shape arithmetic).
fn valid() -> &'static [Vec<u8>; 2] {
    static FILES: OnceLock<[Vec<u8>; 2]> = OnceLock::new();
    FILES.get_or_init(|| [valid_file(ModelKind::ResDd), valid_file(ModelKind::Cnn)])
}

fn check(bytes: &[u8]) -> Result<(), TestCaseError> {
    match TrainedModel::from_bytes(bytes, None) {
        Ok(model) => {
            // What loads, saves to a file that loads to the same bytes.
            let saved = model.to_bytes().expect("a loaded model serialises");
            let again = TrainedModel::from_bytes(&saved, None).expect("reloads");
            prop_assert_eq!(again.to_bytes().expect("serialises"), saved);
        }
        Err(FileError::Malformed(m)) => {
            prop_assert!(MALFORMED_PLACES.iter().any(|p| m.starts_with(p)), "{m}");
        }
        Err(FileError::WrongShape { tensor, .. } | FileError::NonFiniteWeight { tensor, .. }) => {
            prop_assert!(!tensor.is_empty());
        }
        Err(FileError::Model(e)) => prop_assert!(
            matches!(e, ModelError::InvalidSpec(_) | ModelError::UnknownKind(_)),
            "{e}"
        ),
        Err(
            FileError::NotAModelFile
            | FileError::UnknownVersion { .. }
            | FileError::Length { .. }
            | FileError::BadChecksum { .. },
        ) => {}
        Err(other) => prop_assert!(false, "unexpected kind of error: {other}"),
    }
    Ok(())
}

/// One of the valid files with its metadata text mutated, the header made right.
fn mutated_metadata() -> impl Strategy<Value = Vec<u8>> {
    let [resdd, cnn] = valid().clone().map(|f| split(&f));
    let data = [resdd.data, cnn.data];
    prop_oneof![
        mutated(resdd.meta).prop_map(|m| (0, m)),
        mutated(cnn.meta).prop_map(|m| (1, m)),
    ]
    .prop_map(move |(k, meta)| join(&meta, &data[k]))
}

#[test]
fn the_valid_files_load() {
    for f in valid() {
        TrainedModel::from_bytes(f, None).expect("valid");
    }
}

proptest! {
    #![proptest_config(seeded(1500, 0x4D0D_0001))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in arbitrary_bytes(200)) {
        let mut file = decoder::model::MAGIC.to_vec();
        file.extend_from_slice(&bytes);
        check(&bytes)?;
        check(&file)?;
    }

    #[test]
    fn mutated_files_never_panic(
        bytes in prop_oneof![mutated(valid()[0].clone()), mutated(valid()[1].clone())],
    ) {
        // Raw mutations of the whole file, header included: mostly caught by length or checksum.
        check(&bytes)?;
    }

    #[test]
    fn mutated_metadata_never_panics(bytes in mutated_metadata()) {
        check(&bytes)?;
    }

    #[test]
    fn mutated_weights_never_panic(
        which in 0..2usize,
        flips in prop::collection::vec((any::<prop::sample::Index>(), 1u8..), 1..6),
    ) {
        let parts = split(&valid()[which]);
        let mut data = parts.data;
        let n = data.len();
        for (at, mask) in flips {
            data[at.index(n)] ^= mask;
        }
        check(&join(&parts.meta, &data))?;
    }

    #[test]
    fn any_length_claim_is_checked_against_the_bytes_present(
        which in 0..2usize,
        meta_len in prop_oneof![any::<u64>(), 0u64..20_000, Just(1 << 40)],
        body_len in prop::option::of(prop_oneof![any::<u64>(), Just(1u64 << 40)]),
    ) {
        let parts = split(&valid()[which]);
        check(&join_claiming(&parts.meta, &parts.data, meta_len, body_len))?;
    }
}
