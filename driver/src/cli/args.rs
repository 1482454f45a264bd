//! Command-line arguments.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use decoder::model::ModelKind;

/// Technician tool for the handstack prosthesis.
#[derive(Debug, Parser)]
#[command(name = "handctl", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Train a model from a calibration session and write the model file.
    Train(TrainArgs),
    /// Train the named models on a session and score them as in the paper (Tables 3 and 4).
    Eval(EvalArgs),
    /// Write a session directory for the 3DC armband recordings (a proxy calibration).
    #[command(name = "import-3dc")]
    Import3dc(Import3dcArgs),
    /// Run the quality gates on a session and say which trials to redo.
    Check(CheckArgs),
}

/// Training settings shared by train and eval.
#[derive(Debug, Clone, Args)]
pub struct TrainingOpts {
    /// The paper's two-point calibration: flexion and extension only, rest trials unused.
    #[arg(long)]
    pub two_point: bool,
    /// Seed for initialisation, validation split and shuffling.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Upper bound on training epochs (early stopping on held-out trials may end sooner).
    #[arg(long, default_value_t = 200)]
    pub epochs: usize,
    /// Train even when the quality gates find trials to redo.
    #[arg(long)]
    pub ignore_gates: bool,
}

/// `handctl train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Session directory, or 3dc:DIR:train|test.
    pub session: String,
    /// Model file to write (atomically).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Model architecture.
    #[arg(long, default_value = "resdd", value_parser = parse_kind)]
    pub model: ModelKind,
    #[command(flatten)]
    pub training: TrainingOpts,
}

/// `handctl eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Session to train on (and to test on, by its last repetitions, without --test).
    pub session: String,
    /// Models to compare, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "resdd,ln,mlp,cnn", value_parser = parse_kind)]
    pub models: Vec<ModelKind>,
    /// Session to test on; without it the last repetition of every trial kind is held out.
    #[arg(long)]
    pub test: Option<String>,
    /// Directory for the PNG figures (ROC and interpolation curves per model).
    #[arg(long)]
    pub plots: Option<PathBuf>,
    #[command(flatten)]
    pub training: TrainingOpts,
}

/// `handctl import-3dc`.
#[derive(Debug, Args)]
pub struct Import3dcArgs {
    /// Directory holding P4_{train,test}_emg.npy and P4_{train,test}_index.csv.
    pub dir: PathBuf,
    /// Which half of the recordings.
    #[arg(long, value_parser = ["train", "test"])]
    pub split: String,
    /// Session directory to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// `handctl check`.
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// Session directory, or 3dc:DIR:train|test.
    pub session: String,
}

fn parse_kind(s: &str) -> Result<ModelKind, String> {
    s.parse::<ModelKind>().map_err(|e| e.to_string())
}
