//! Where the tests find the 3DC participants' recordings (../shared/data), with a clear failure
//! when they are missing.

use std::path::PathBuf;

/// The folder of participant `participant` (4, 6 or 7); panics naming it when it is missing.
pub fn data_dir(participant: u32) -> PathBuf {
    let d = PathBuf::from(format!(
        "{}/../../shared/data/3dc-armband-p{participant}",
        env!("CARGO_MANIFEST_DIR")
    ));
    assert!(
        d.join(format!("P{participant}_train_emg.npy")).exists(),
        "{} is missing: the tests read the real recordings from ../shared/data",
        d.display()
    );
    d
}
