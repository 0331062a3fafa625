//! Flash of `solve5_f32` (see `size_main!`).
#![no_std]
#![no_main]

m4_numerics::size_main!(|x: f32| m4_numerics::solve5::<f32>(
    core::hint::black_box([[x; 5]; 5]),
    core::hint::black_box([x; 5])
));
