//! A field made a block of x-columns at a time, each block on its own (as Dask workers make
//! them): every block holds the whole field's records there, bit for bit.

use sylva_wind::synth::synthesize_columns;
use sylva_wind::{Grid, Method, SynthParams, WindField, WindParams};

#[test]
fn blocks_of_columns_made_alone_are_the_whole_fields_columns_bit_for_bit() {
    // Several heights and the advection on (the reference coherence speed: separable), 70
    // columns so that blocks straddle the synthesis's own 32-column batches.
    let params = WindParams { u_star: 1.4, ..WindParams::default() };
    let grid = Grid::regular(70, 5, 3.0, &[8.0, 15.0, 22.0], 128, 0.1);
    let sp = SynthParams { seed: 11, method: Method::Separable };
    let whole = WindField::generate(&params, &grid, sp, &|_| {}).expect("field");
    let (np, m, nx) = (grid.nz() * grid.ny(), grid.frames, grid.nx());
    for cols in [0..70, 0..1, 5..6, 30..34, 31..64, 33..70, 69..70] {
        let block = synthesize_columns(&params, &grid, sp, cols.clone()).expect("block");
        let w = cols.len();
        assert_eq!(block.len(), m * 3 * np * w);
        for t in 0..m {
            for q in 0..3 * np {
                let row = &block[(t * 3 * np + q) * w..][..w];
                let full = &whole.data[(t * 3 * np + q) * nx + cols.start..][..w];
                let same = row.iter().zip(full).all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(same, "columns {cols:?}, frame {t}, row {q}: {row:?} against {full:?}");
            }
        }
    }
    // A block outside the grid, or empty, is refused with the range in the message.
    for cols in [0..0, 60..71] {
        let e = synthesize_columns(&params, &grid, sp, cols).expect_err("bad range");
        assert!(e.to_string().contains("x-columns"), "{e}");
    }
    // The methods that hold every point at once cannot make a block alone.
    let dense = SynthParams { method: Method::Embedding, ..sp };
    assert!(synthesize_columns(&params, &grid, dense, 0..4).is_err());
}
