//! [`Shared`]: a value either borrowed for `'a` or owned through an [`Arc`], so that the
//! [`crate::Locator`] and the [`crate::Interpolator`] can borrow a mesh (tests, tools) or
//! own it (a flow kept in a long-lived resource) with one type and no leak.

use std::ops::Deref;
use std::sync::Arc;

/// A borrowed or `Arc`-shared `T`; dereferences to `T`.
#[derive(Debug)]
pub enum Shared<'a, T> {
    /// Borrowed for `'a`.
    Borrowed(&'a T),
    /// Shared ownership: freed with the last `Arc`.
    Owned(Arc<T>),
}

impl<T> Clone for Shared<'_, T> {
    fn clone(&self) -> Self {
        match self {
            Shared::Borrowed(r) => Shared::Borrowed(r),
            Shared::Owned(a) => Shared::Owned(Arc::clone(a)),
        }
    }
}

impl<T> Deref for Shared<'_, T> {
    type Target = T;
    #[inline(always)]
    fn deref(&self) -> &T {
        match self {
            Shared::Borrowed(r) => r,
            Shared::Owned(a) => a,
        }
    }
}

impl<T> Shared<'_, T> {
    /// The `Arc` when owned (`None` when borrowed).
    pub fn arc(&self) -> Option<&Arc<T>> {
        match self {
            Shared::Borrowed(_) => None,
            Shared::Owned(a) => Some(a),
        }
    }
}
