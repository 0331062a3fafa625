//! Flash of `base` (see `size_main!`).
#![no_std]
#![no_main]

m4_numerics::size_main!(|x: f32| x);
