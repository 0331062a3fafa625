//! Flash of `libm` (see `size_main!`).
#![no_std]
#![no_main]

m4_numerics::size_main!(|x: f32| m4_numerics::libm_sincos(core::hint::black_box(x)));
