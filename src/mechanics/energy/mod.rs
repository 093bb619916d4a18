//! Energy terms on the grid, with analytic gradients and sparse Hessians.
