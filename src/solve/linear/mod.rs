//! Distributed sparse linear algebra: block-sparse matrix, GMRES, block Jacobi.
