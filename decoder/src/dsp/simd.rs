//! Runtime choice of the instruction set the signal chain's inner loops are compiled for.
//!
//! The filters and features are plain portable loops over fixed 4-lane accumulators (features)
//! or over the channels (filters). A default x86_64 build may only assume SSE2, two f64 lanes
//! per instruction; [`Simd::detect`] finds AVX2 or AVX-512 at run time (through `pulp`, whose
//! safe API runs a closure inside a function compiled with those features) and the very same
//! source is then compiled a second time, four lanes wide or more. A few kernels are written
//! with explicit vectors for one instruction set: the filter cascade and the model's
//! matrix-vector product for AVX2, the features' two-window passes for AVX-512.
//!
//! Both builds give the same bits: every operation is an IEEE-754 add, subtract, multiply,
//! divide, square root or absolute value, each correctly rounded whatever the vector width;
//! Rust never reassociates floating-point sums and never contracts `a * b + c` into a fused
//! multiply-add, so each lane sees the same operations in the same order, and the final lane
//! reduction is the same scalar code. Tests check it on random and real windows.
//! On aarch64 NEON is part of the baseline, so the portable build is already the vector one.

/// Which build of the inner loops runs: the portable one, or the one for the widest
/// instruction set the CPU has (AVX2 or AVX-512 on x86_64). The same results bit for bit; the
/// choice is speed only. `Copy`, a few bytes; detected once and kept.
#[derive(Debug, Clone, Copy)]
pub struct Simd {
    arch: Option<pulp::Arch>,
    /// AVX2 (with the rest of x86-64-v3), for kernels written with explicit vectors.
    #[cfg(target_arch = "x86_64")]
    v3: Option<pulp::x86::V3>,
    /// AVX-512 (x86-64-v4), for the features' two-window kernel.
    #[cfg(target_arch = "x86_64")]
    v4: Option<pulp::x86::V4>,
}

impl Simd {
    /// The widest instruction set this CPU has (checked at run time).
    pub fn detect() -> Simd {
        Simd {
            arch: Some(pulp::Arch::new()),
            #[cfg(target_arch = "x86_64")]
            v3: pulp::x86::V3::try_new(),
            #[cfg(target_arch = "x86_64")]
            v4: pulp::x86::V4::try_new(),
        }
    }

    /// The portable build only (the reference the dispatched build is tested against).
    pub fn portable() -> Simd {
        Simd {
            arch: None,
            #[cfg(target_arch = "x86_64")]
            v3: None,
            #[cfg(target_arch = "x86_64")]
            v4: None,
        }
    }

    /// This build without its AVX-512 kernels (the AVX2 ones and the dispatched loops stay):
    /// for tests and benchmarks that compare the kernels on a machine that has AVX-512.
    pub fn without_avx512(self) -> Simd {
        #[cfg(target_arch = "x86_64")]
        return Simd { v4: None, ..self };
        #[cfg(not(target_arch = "x86_64"))]
        self
    }

    /// The AVX2 token, when this is the dispatched build and the CPU has it: for kernels
    /// written with explicit four-lane vectors (`V3::vectorize` compiles them for it).
    #[cfg(target_arch = "x86_64")]
    pub(crate) fn x86_v3(self) -> Option<pulp::x86::V3> {
        self.v3
    }

    /// The AVX-512 token, when this is the dispatched build and the CPU has it: for kernels
    /// written with explicit eight-lane vectors.
    #[cfg(target_arch = "x86_64")]
    pub(crate) fn x86_v4(self) -> Option<pulp::x86::V4> {
        self.v4
    }

    /// The instruction set of the explicit kernels this build runs, for reports: `"AVX-512"`,
    /// `"AVX2"` or `"portable"` (on aarch64 always `"portable"`, NEON being the baseline).
    pub fn name(self) -> &'static str {
        #[cfg(target_arch = "x86_64")]
        {
            if self.v4.is_some() {
                return "AVX-512";
            }
            if self.v3.is_some() {
                return "AVX2";
            }
        }
        "portable"
    }

    /// Runs `f`, compiled for the chosen instruction set. Everything `f` calls that should be
    /// vectorised must be `#[inline(always)]`, so that it is compiled inside `f`.
    #[inline(always)]
    pub(crate) fn run<R>(self, f: impl FnOnce() -> R) -> R {
        match self.arch {
            Some(arch) => arch.dispatch(f),
            None => f(),
        }
    }
}

impl Default for Simd {
    /// [`Simd::detect`].
    fn default() -> Simd {
        Simd::detect()
    }
}
