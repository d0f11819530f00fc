//! Cooperative cancellation: a stop request that long computations look at in cheap places.
//!
//! A caller that may want to stop a computation early (the Python bindings on Ctrl-C) makes a
//! [`Token`], runs the computation inside [`Token::scope`] and calls [`Token::cancel`] from another
//! thread when it should stop. The computation asks [`requested`] now and then: the integrators
//! every [`CHECK_EVERY`] steps (the scalar driver, the lane-batched loops), the describing
//! function's grid scan every [`CHECK_EVERY`] grid points, continuation and curve loops once per
//! point. A cancelled computation ends early with what it has: an integration with
//! `Outcome::Cancelled`, a batch with its unstarted items marked as not computed. Its results are
//! incomplete by design; a caller that cancelled discards them (the bindings raise
//! `KeyboardInterrupt` instead).
//!
//! The token is per thread: [`Token::scope`] makes it the current thread's, and
//! [`crate::parallel::par_map`] hands the caller's token to its worker threads, so that one call's
//! cancellation stops that call's work and nothing else in the process. Without a token (a plain
//! Rust caller, a test) [`requested`] is always false.
//!
//! This module is a leaf: it refers to no other module of the crate, so the generic integrators in
//! `ode` may use it without knowing anything of the layers above.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Integrator steps (or grid points) between two looks at the stop request: at most about a
/// millisecond of work on the slider's six states, a few on the shooting's 42, and a cost per step
/// below the noise of any timing (one thread-local read in 256 steps).
pub const CHECK_EVERY: u64 = 256;

/// The reason text of work left undone because the computation was cancelled.
pub const CANCELLED: &str = "cancelled: the computation was interrupted before this item finished";

/// A stop request shared by one computation and whoever may cancel it (cheap to clone).
#[derive(Clone, Debug, Default)]
pub struct Token(Arc<AtomicBool>);

impl Token {
    /// A fresh, uncancelled token.
    pub fn new() -> Self {
        Token::default()
    }

    /// Ask every computation running under this token to stop (from any thread).
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`Token::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// Run `f` on this thread with this token as the current one (restored afterwards, also when
    /// `f` panics).
    pub fn scope<R>(&self, f: impl FnOnce() -> R) -> R {
        struct Restore(Option<Token>);
        impl Drop for Restore {
            fn drop(&mut self) {
                let prev = self.0.take();
                CURRENT.with(|c| *c.borrow_mut() = prev);
            }
        }
        let prev = CURRENT.with(|c| c.borrow_mut().replace(self.clone()));
        let _restore = Restore(prev);
        f()
    }
}

thread_local! {
    static CURRENT: RefCell<Option<Token>> = const { RefCell::new(None) };
}

/// The current thread's token, if it runs inside a [`Token::scope`] (to hand to worker threads).
pub fn current() -> Option<Token> {
    CURRENT.with(|c| c.borrow().clone())
}

/// Whether the computation running on this thread was asked to stop.
#[inline]
pub fn requested() -> bool {
    CURRENT.with(|c| c.borrow().as_ref().is_some_and(Token::is_cancelled))
}

/// [`requested`], looked at only when `count` is a multiple of [`CHECK_EVERY`] (the cheap form for
/// a loop counter).
#[inline]
pub fn requested_every(count: u64) -> bool {
    count.is_multiple_of(CHECK_EVERY) && requested()
}

/// Run `f` with `token` as the current thread's token when there is one, else as it is.
pub fn scope_opt<R>(token: Option<&Token>, f: impl FnOnce() -> R) -> R {
    match token {
        Some(t) => t.scope(f),
        None => f(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_token_is_seen_only_inside_its_scope_and_on_its_thread() {
        assert!(!requested());
        let t = Token::new();
        t.cancel();
        assert!(!requested(), "outside any scope nothing is requested");
        t.scope(|| {
            assert!(requested());
            assert!(requested_every(0) && !requested_every(1) && requested_every(CHECK_EVERY));
            // Another thread does not see this thread's token.
            std::thread::scope(|s| s.spawn(|| assert!(!requested())).join().unwrap());
            // A nested scope with a fresh token hides the outer one, and restores it.
            Token::new().scope(|| assert!(!requested()));
            assert!(requested());
        });
        assert!(!requested());
    }

    #[test]
    fn the_scope_is_restored_after_a_panic() {
        let t = Token::new();
        t.cancel();
        let prev = std::panic::take_hook();
        std::panic::set_hook(Box::new(|_| {}));
        let r = std::panic::catch_unwind(|| t.scope(|| panic!("boom")));
        std::panic::set_hook(prev);
        assert!(r.is_err());
        assert!(!requested());
    }

    #[test]
    fn cancel_from_another_thread_is_seen() {
        let t = Token::new();
        let seen = t.scope(|| {
            let t2 = current().expect("inside a scope");
            std::thread::scope(|s| s.spawn(move || t2.cancel()).join().unwrap());
            requested()
        });
        assert!(seen);
    }
}
