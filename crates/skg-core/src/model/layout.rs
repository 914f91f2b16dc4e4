//! The node-local variables `u = [q, v, λ, w, dw, μ]` of the density `s` and their
//! index ranges ([`LocalLayout`]); the time `t` is a tape input after them, and after
//! it the free parameters `θ` of a fit's model (none otherwise).

/// Index ranges of the node-local variable vector `u = [q, v, λ, w, dw, μ]`.
#[derive(Debug, Clone, Copy)]
pub struct LocalLayout {
    /// Number of coordinates.
    pub d: usize,
    /// Number of velocity constraints.
    pub n: usize,
    /// Number of free parameters `θ`: tape inputs after the time (a fit's model; 0
    /// otherwise).
    pub free: usize,
}

/// Which of the six blocks a local variable belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LocalKind {
    /// q = q+, a coordinate.
    Q,
    /// v = Dq+, a velocity.
    V,
    /// λ = λ+, a constraint multiplier.
    Lambda,
    /// w = q-.
    W,
    /// dw = Dq-.
    Dw,
    /// μ = λ-.
    Mu,
}

impl LocalKind {
    /// Plus-type variables (q+, Dq+, λ+) as opposed to minus-type (q-, Dq-, λ-).
    pub fn is_plus(self) -> bool {
        matches!(self, LocalKind::Q | LocalKind::V | LocalKind::Lambda)
    }
}

impl LocalLayout {
    /// Number of local variables u = [q, v, λ, w, dw, μ].
    pub fn len(&self) -> usize {
        4 * self.d + 2 * self.n
    }

    /// True only for a scene without coordinates (rejected by validation).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index of the time `t` in a tape's inputs: after the local variables. It is an
    /// input, not a local variable: nothing is differentiated with respect to it.
    pub fn time(&self) -> usize {
        self.len()
    }

    /// Number of a tape's inputs: the local variables `u`, the time and the free
    /// parameters.
    pub fn inputs(&self) -> usize {
        self.len() + 1 + self.free
    }

    /// Index of the free parameter `θ_j` in a tape's inputs: after the time.
    pub fn theta(&self, j: usize) -> usize {
        self.len() + 1 + j
    }

    /// Index of q_i.
    pub fn q(&self, i: usize) -> usize {
        i
    }

    /// Index of v_i.
    pub fn v(&self, i: usize) -> usize {
        self.d + i
    }

    /// Index of λ_a.
    pub fn lambda(&self, a: usize) -> usize {
        2 * self.d + a
    }

    /// Index of w_i.
    pub fn w(&self, i: usize) -> usize {
        2 * self.d + self.n + i
    }

    /// Index of dw_i.
    pub fn dw(&self, i: usize) -> usize {
        3 * self.d + self.n + i
    }

    /// Index of μ_a.
    pub fn mu(&self, a: usize) -> usize {
        4 * self.d + self.n + a
    }

    /// Kind and component of local variable `k`.
    pub fn kind(&self, k: usize) -> (LocalKind, usize) {
        let (d, n) = (self.d, self.n);
        if k < d {
            (LocalKind::Q, k)
        } else if k < 2 * d {
            (LocalKind::V, k - d)
        } else if k < 2 * d + n {
            (LocalKind::Lambda, k - 2 * d)
        } else if k < 3 * d + n {
            (LocalKind::W, k - 2 * d - n)
        } else if k < 4 * d + n {
            (LocalKind::Dw, k - 3 * d - n)
        } else {
            (LocalKind::Mu, k - 4 * d - n)
        }
    }
}
