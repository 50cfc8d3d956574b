//! The three synthesis methods, one component at a time: the coefficients of every point
//! and frequency line, handed to the emitter a column of points at a time.

use super::*;

/// The separable method: the AR(1) recursions along x, y and z per frequency line, a
/// column of points at a time (exact where one speed divides every separation). Emits the
/// x-columns `columns`; before them only the x recursion runs, to carry its state.
pub(super) fn separable<T: Sample>(
    params: &WindParams,
    grid: &Grid,
    comp: Component,
    lines: &Lines,
    emitter: &mut Emitter<'_, T>,
    columns: std::ops::Range<usize>,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<(), WindError> {
    let (nx, ny, nz) = (grid.nx(), grid.ny(), grid.nz());
    let nc = lines.nc;
    let col_len = nz * ny * nc;
    let cc = params.coherence[comp.index()];
    let gaps = |axis: &[f64], c: f64| -> Vec<(Vec<f64>, Vec<f64>)> {
        axis.windows(2).map(|w| lines.ar1(c, w[1] - w[0])).collect()
    };
    let (gx, gy, gz) = (gaps(&grid.xs, cc.cx), gaps(&grid.ys, cc.cy), gaps(&grid.zs, cc.cz));
    // L_x acts along x on each point row, L_y ⊗ L_z across rows; they commute, so
    // the x recursion runs first on the raw phasors and its state is carried from
    // column to column, and the y and z recursions run within each column.
    let mut xstate = vec![C64::default(); col_len];
    let mut col = vec![C64::default(); col_len];
    let mut fac = vec![C64::default(); nz * nc];
    // Lines are independent until the FFT: each task takes a range of lines and
    // walks every point row of the column, so a row's state stays in cache between
    // its x step, its y step and the next row's y step.
    const LINES_PER_TASK: usize = 128;
    let ranges: Vec<std::ops::Range<usize>> = (1..nc - 1)
        .step_by(LINES_PER_TASK)
        .map(|j0| j0..(j0 + LINES_PER_TASK).min(nc - 1))
        .collect();
    for ix in 0..columns.end {
        let emitted = ix >= columns.start;
        // √Δω·√S0(z) times this column's advection factor, per (height, line): one
        // complex factor applied at emission.
        if emitted {
            lines.column_factors(params.advection, grid.xs[ix], true, &mut fac);
        }
        let (xs_ptr, col_ptr) =
            (RowsPtr(xstate.as_mut_ptr(), xstate.len()), RowsPtr(col.as_mut_ptr(), col.len()));
        ranges.par_iter().for_each(|r| {
            let at = |p: usize| p * nc + r.start;
            fn part<'v>(v: &'v [f64], r: &std::ops::Range<usize>) -> &'v [f64] {
                &v[r.clone()]
            }
            for iz in 0..nz {
                for iy in 0..ny {
                    let p = iz * ny + iy;
                    // SAFETY: this task alone touches lines `r` of every row; rows p
                    // and p − 1 are disjoint ranges of `col`.
                    let (x, out, prev) = unsafe {
                        (
                            xs_ptr.slice(at(p), r.len()),
                            col_ptr.slice(at(p), r.len()),
                            (iy > 0).then(|| &*col_ptr.slice(at(p - 1), r.len())),
                        )
                    };
                    let k = (p * nx + ix) as u64; // Cholesky column of point (ix, iy, iz)
                    let ar = (ix > 0).then(|| (part(&gx[ix - 1].0, r), part(&gx[ix - 1].1, r)));
                    phasor_row(&lines.keys[r.clone()], k, x, ar);
                    if !emitted {
                        continue;
                    }
                    let ay = if iy > 0 {
                        (part(&gy[iy - 1].0, r), part(&gy[iy - 1].1, r))
                    } else {
                        (&[][..], &[][..])
                    };
                    y_row(x, prev, ay, out);
                }
            }
            for iz in (1..nz).filter(|_| emitted) {
                let (rho, s) = (part(&gz[iz - 1].0, r), part(&gz[iz - 1].1, r));
                for iy in 0..ny {
                    let (p, q) = ((iz - 1) * ny + iy, iz * ny + iy);
                    // SAFETY: as above; rows p and q differ.
                    let (prev, cur) =
                        unsafe { (&*col_ptr.slice(at(p), r.len()), col_ptr.slice(at(q), r.len())) };
                    ar1_step(prev, cur, rho, s);
                }
            }
        });
        if emitted {
            emitter.push(ix, Col::Wide(&col), &fac)?;
        }
        progress((ix + 1) as f64 / columns.end as f64);
    }

    Ok(())
}

/// The paper's dense method: per frequency line the cross-spectral matrix of every pair of
/// points and its Cholesky factor, in f64 (the reference for small grids).
pub(super) fn cholesky<T: Sample>(
    params: &WindParams,
    grid: &Grid,
    comp: Component,
    lines: &Lines,
    emitter: &mut Emitter<'_, T>,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<(), WindError> {
    let (nx, ny, nz) = (grid.nx(), grid.ny(), grid.nz());
    let nc = lines.nc;
    let col_len = nz * ny * nc;
    let n = grid.points();
    let pos = |k: usize| {
        let (ix, iy, iz) = (k % nx, (k / nx) % ny, k / (nx * ny));
        [grid.xs[ix], grid.ys[iy], grid.zs[iz], params.mean_speed(grid.zs[iz])]
    };
    let pts: Vec<[f64; 4]> = (0..n).map(pos).collect();
    // Coefficients laid out (x, z, y, j): one column after another.
    let mut block = vec![C64::default(); nx * col_len];
    let mut mat = vec![0.0f64; n * n];
    let mut e = vec![C64::default(); n];
    for j in 1..nc - 1 {
        let f = lines.omega[j] / (2.0 * PI);
        for a in 0..n {
            let sa = lines.scale[(a / (nx * ny)) * nc + j];
            for b in 0..=a {
                let sb = lines.scale[(b / (nx * ny)) * nc + j];
                let d = [pts[a][0] - pts[b][0], pts[a][1] - pts[b][1], pts[a][2] - pts[b][2]];
                let um = match params.coherence_speed {
                    CoherenceSpeed::Reference => lines.u_ref,
                    CoherenceSpeed::PairMean => 0.5 * (pts[a][3] + pts[b][3]),
                };
                // √S0_a √S0_b Coh_ab (the √Δω factors are applied at emission).
                let s0 = sa * sb / lines.sqrt_dw.powi(2);
                mat[a * n + b] = s0 * spectrum::coherence(params, comp, f, d, um);
            }
        }
        cholesky_lower(&mut mat, n).map_err(|row| {
            WindError::Unsupported(format!(
                "CPSDM not positive definite at line {j} (f = {f:.4} Hz), row {row}"
            ))
        })?;
        for (k, ek) in e.iter_mut().enumerate() {
            *ek = phasor(lines.keys[j], k as u64);
        }
        for a in 0..n {
            let row = &mat[a * n..a * n + a + 1];
            let v: C64 = row.iter().zip(&e).map(|(l, ek)| ek * *l).sum();
            let (ix, p) = (a % nx, a / nx);
            block[ix * col_len + p * nc + j] = v;
        }
        progress(j as f64 / (nc - 2) as f64);
    }
    // The dense factor already holds √S0: emit with √Δω and the advection alone.
    let mut fac = vec![C64::default(); nz * nc];
    for (ix, col) in block.chunks(col_len).enumerate() {
        lines.column_factors(params.advection, grid.xs[ix], false, &mut fac);
        emitter.push(ix, Col::Wide(col), &fac)?;
    }

    Ok(())
}

/// Circulant embedding across x and y with one dense block per horizontal wavenumber (the
/// pair-mean coherence on several heights); returns the bound on the coherence error.
pub(super) fn embedding<T: Sample>(
    params: &WindParams,
    grid: &Grid,
    comp: Component,
    lines: &Lines,
    emitter: &mut Emitter<'_, T>,
    spare: &mut Vec<Complex<T>>,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<f64, WindError> {
    let (nx, ny, nz) = (grid.nx(), grid.ny(), grid.nz());
    let nc = lines.nc;
    let col_len = nz * ny * nc;
    let emb = embed::Embedding::<T>::new(params, grid, comp, lines.u_ref)?;
    // Coefficients laid out (x, z, y, j), one column after another; every line is
    // independent and fills its own index j of every point.
    // Every entry is written below, so a block left by the previous component (the same
    // size) is taken as it is: no second gigabyte to fault in on a large grid.
    let mut block = std::mem::take(spare);
    block.resize(nx * col_len, Complex::default());
    let out = OutPtr(block.as_mut_ptr(), block.len());
    let done = std::sync::atomic::AtomicUsize::new(0);
    let worst = std::sync::Mutex::new(0.0f64);
    let kappas = emb.wavenumbers();
    // Tasks take runs of consecutive lines, keep each line's field whole, then write each
    // point's run of lines at once: one burst per point instead of one scattered write per
    // point and line.
    const RUN: usize = 16;
    let np = nz * ny * nx;
    let runs: Vec<usize> = (1..nc - 1).step_by(RUN).collect();
    // Runs go to the threads as they free up (rayon's splitting, so a core slowed by other
    // work hands part of its share on); each piece of work makes its buffers (several MB)
    // once. The output does not depend on the split: every line draws its own phasors.
    runs.par_iter().for_each_init(
        || (emb.scratch(), vec![Complex::<T>::default(); np * RUN]),
        |(s, staged), &j0| {
            let j1 = (j0 + RUN).min(nc - 1);
            for j in j0..j1 {
                let key = lines.keys[j];
                let xi = |m: usize, k0: usize, out: &mut [Complex<T>]| {
                    T::phasors(key, (m * kappas + k0) as u64, out)
                };
                let f = lines.omega[j] / (2.0 * PI);
                let w = &mut staged[(j - j0) * np..(j - j0 + 1) * np];
                let clipped = emb.line(f, &xi, s, w);
                if clipped > 0.0
                    && let Ok(mut w) = worst.lock()
                {
                    *w = w.max(clipped);
                }
            }
            // The fields come in the block's point order (x, z, y): both sides run forwards.
            for q in 0..np {
                let at = q * nc + j0;
                for d in 0..j1 - j0 {
                    // SAFETY: lines j0 … j1 of every point belong to this task alone,
                    // and the index lies inside `block` (nx · nz · ny · nc entries).
                    unsafe { out.write(at + d, staged[d * np + q]) };
                }
            }
            let d = done.fetch_add(j1 - j0, std::sync::atomic::Ordering::Relaxed);
            progress((d + j1 - j0) as f64 / (nc - 2) as f64);
        },
    );
    let coherence_error = worst.into_inner().unwrap_or(f64::INFINITY);
    let mut fac = vec![C64::default(); nz * nc];
    for (ix, col) in block.chunks(col_len).enumerate() {
        lines.column_factors(params.advection, grid.xs[ix], true, &mut fac);
        emitter.push(ix, Col::Own(col), &fac)?;
    }
    *spare = block;
    Ok(coherence_error)
}
