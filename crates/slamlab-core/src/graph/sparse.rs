//! The sparse Cholesky factorization behind the graph solvers, behind a small
//! trait so that the solver reads as the algorithm: analyse the pattern once,
//! factorize the numbers every iteration, solve.
//!
//! The implementation is faer's sparse `L Lᵀ` (simplicial or supernodal, chosen by
//! faer), built without threads so that it runs in WebAssembly. The fill-reducing
//! ordering is an approximate minimum degree (AMD) ordering computed on the
//! *vertex* graph ([`fill_reducing_order`]); the solver numbers its unknowns in that
//! order, so faer factorizes with the identity ordering.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use thiserror::Error;

/// Why a sparse factorization or solve failed.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum CholeskyError {
    /// The pattern could not be analysed (inconsistent structure, out of memory).
    #[error("the sparsity pattern could not be analysed: {0}")]
    Analysis(String),
    /// The matrix is not numerically positive definite: pivot `column` (in the
    /// factor's own ordering of unknowns) was zero, negative or NaN.
    #[error("the matrix is not positive definite at unknown {column}")]
    NotPositiveDefinite {
        /// The failing unknown.
        column: usize,
    },
    /// `factorize` was given a number of values that does not match the pattern,
    /// or `solve` was called without a successful `factorize`.
    #[error("sparse Cholesky used out of order: {0}")]
    Usage(&'static str),
}

/// A sparse Cholesky factorization `A = L Lᵀ` of a symmetric positive-definite
/// matrix given by the upper triangle of its pattern in compressed-column form.
pub trait SparseCholesky: Sized {
    /// Symbolic analysis, done once per pattern: `col_ptr` (n + 1 entries) and
    /// `row_idx` (sorted rows `≤` column in each column) of the upper triangle.
    fn analyze(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Result<Self, CholeskyError>;
    /// Numeric factorization with the values of the pattern given to `analyze`,
    /// reusing the symbolic analysis.
    fn factorize(&mut self, values: &[f64]) -> Result<(), CholeskyError>;
    /// Solves `A x = b` in place (`rhs` holds `b` and receives `x`).
    fn solve_in_place(&mut self, rhs: &mut [f64]) -> Result<(), CholeskyError>;
    /// Number of non-zeros of `L` (with the diagonal).
    fn factor_nonzeros(&self) -> usize;
}

/// faer's sparse `L Lᵀ`, single-threaded.
pub struct FaerCholesky {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    factor_mem: MemBuffer,
    solve_mem: MemBuffer,
    factorized: bool,
}

impl std::fmt::Debug for FaerCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FaerCholesky")
            .field("n", &self.n)
            .field("nonzeros_of_h", &self.row_idx.len())
            .field("nonzeros_of_l", &self.l_values.len())
            .field("factorized", &self.factorized)
            .finish()
    }
}

impl SparseCholesky for FaerCholesky {
    fn analyze(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Result<Self, CholeskyError> {
        let pattern_ok = col_ptr.len() == n + 1
            && col_ptr.first() == Some(&0)
            && col_ptr.windows(2).all(|w| w[0] <= w[1])
            && col_ptr.last() == Some(&row_idx.len())
            && (0..n).all(|c| {
                let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
                rows.windows(2).all(|w| w[0] < w[1]) && rows.iter().all(|&r| r <= c)
            });
        if !pattern_ok {
            return Err(CholeskyError::Analysis(
                "the column pointers or row indices are inconsistent".to_owned(),
            ));
        }
        let pattern = SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            pattern,
            Side::Upper,
            SymmetricOrdering::Identity,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| CholeskyError::Analysis(format!("{e:?}")))?;
        let factor_req =
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
        let solve_req = symbolic.solve_in_place_scratch::<f64>(1, Par::Seq);
        let factor_mem = MemBuffer::try_new(factor_req)
            .map_err(|_| CholeskyError::Analysis("out of memory".to_owned()))?;
        let solve_mem = MemBuffer::try_new(solve_req)
            .map_err(|_| CholeskyError::Analysis("out of memory".to_owned()))?;
        let l_values = vec![0.0; symbolic.len_val()];
        Ok(Self {
            n,
            col_ptr: col_ptr.to_vec(),
            row_idx: row_idx.to_vec(),
            symbolic,
            l_values,
            factor_mem,
            solve_mem,
            factorized: false,
        })
    }

    fn factorize(&mut self, values: &[f64]) -> Result<(), CholeskyError> {
        self.factorized = false;
        if values.len() != self.row_idx.len() {
            return Err(CholeskyError::Usage("wrong number of values"));
        }
        if let Some(c) = (0..self.n).find(|&c| {
            let d = self.col_ptr[c + 1];
            !(d > self.col_ptr[c] && self.row_idx[d - 1] == c && values[d - 1] > 0.0)
        }) {
            // A zero, negative or NaN diagonal entry: not positive definite.
            return Err(CholeskyError::NotPositiveDefinite { column: c });
        }
        let pattern = SymbolicSparseColMatRef::new_checked(
            self.n,
            self.n,
            &self.col_ptr,
            None,
            &self.row_idx,
        );
        let a = SparseColMatRef::new(pattern, values);
        self.symbolic
            .factorize_numeric_llt(
                &mut self.l_values,
                a,
                Side::Upper,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut self.factor_mem),
                Default::default(),
            )
            .map_err(|e| match e {
                // faer reports the pivot one past the failing column.
                faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                    CholeskyError::NotPositiveDefinite {
                        column: index.saturating_sub(1).min(self.n.saturating_sub(1)),
                    }
                }
            })?;
        if self.l_values.iter().any(|v| !v.is_finite()) {
            return Err(CholeskyError::NotPositiveDefinite { column: 0 });
        }
        self.factorized = true;
        Ok(())
    }

    fn solve_in_place(&mut self, rhs: &mut [f64]) -> Result<(), CholeskyError> {
        if !self.factorized {
            return Err(CholeskyError::Usage("solve before a successful factorize"));
        }
        if rhs.len() != self.n {
            return Err(CholeskyError::Usage("right-hand side of the wrong length"));
        }
        let llt = LltRef::new(&self.symbolic, &self.l_values);
        let n = self.n;
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            MemStack::new(&mut self.solve_mem),
        );
        Ok(())
    }

    fn factor_nonzeros(&self) -> usize {
        self.symbolic.len_val()
    }
}

/// A fill-reducing elimination order of a symmetric graph with `n` nodes given by
/// its adjacency lists (each edge listed once or twice; self-loops ignored):
/// approximate minimum degree (Amestoy, Davis and Duff), via faer. Returns
/// `order[k]` = the node eliminated `k`-th. Falls back to the natural order if AMD
/// cannot run.
pub fn fill_reducing_order(n: usize, adjacency: &[Vec<usize>]) -> Vec<usize> {
    use faer::sparse::linalg::amd;
    let natural: Vec<usize> = (0..n).collect();
    // Upper-triangular pattern (row < column) with sorted, unique rows.
    let mut columns: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (a, list) in adjacency.iter().enumerate() {
        for &b in list {
            if a < b && b < n {
                columns[b].push(a);
            } else if b < a {
                columns[a].push(b);
            }
        }
    }
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0);
    for col in &mut columns {
        col.sort_unstable();
        col.dedup();
        row_idx.extend_from_slice(col);
        col_ptr.push(row_idx.len());
    }
    let pattern = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
    let mut perm = vec![0usize; n];
    let mut perm_inv = vec![0usize; n];
    let Ok(mut mem) = MemBuffer::try_new(amd::order_scratch::<usize>(n, row_idx.len())) else {
        return natural;
    };
    match amd::order(
        &mut perm,
        &mut perm_inv,
        pattern,
        amd::Control::default(),
        MemStack::new(&mut mem),
    ) {
        Ok(_) => perm,
        Err(_) => natural,
    }
}

/// The pattern of the Cholesky factor `L` (lower triangle, by columns) of a
/// symmetric matrix whose graph is `adjacency`, eliminated in the natural order
/// `0, 1, …, n−1`: the symbolic factorization by elimination (George and Liu).
/// Column `j` of `L` holds `j` and every node that is a neighbour of `j` or of a
/// node eliminated before `j` whose own column reached `j`. Returns, per column,
/// its sorted rows below the diagonal.
pub fn symbolic_factor_pattern(adjacency: &[Vec<usize>]) -> Vec<Vec<usize>> {
    let n = adjacency.len();
    let mut columns: Vec<Vec<usize>> = vec![Vec::new(); n];
    // children[p]: columns whose first off-diagonal row (their parent in the
    // elimination tree) is p.
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut mark = vec![usize::MAX; n];
    for j in 0..n {
        let mut rows = Vec::new();
        mark[j] = j;
        for &i in &adjacency[j] {
            if i > j && i < n && mark[i] != j {
                mark[i] = j;
                rows.push(i);
            }
        }
        for &c in &children[j] {
            for &i in &columns[c] {
                if i > j && mark[i] != j {
                    mark[i] = j;
                    rows.push(i);
                }
            }
        }
        rows.sort_unstable();
        if let Some(&parent) = rows.first() {
            children[parent].push(j);
        }
        columns[j] = rows;
    }
    columns
}
