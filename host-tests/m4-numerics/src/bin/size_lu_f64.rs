//! Flash of `lu_f64` (see `size_main!`).
#![no_std]
#![no_main]

m4_numerics::size_main!(|x: f32| m4_numerics::lu::<f64>(
    core::hint::black_box([[f64::from(x); 5]; 5]),
    core::hint::black_box([f64::from(x); 5])
));
