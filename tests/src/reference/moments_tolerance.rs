use super::Query;
use super::cpu::Prefiltered;
use super::tolerance::Allowed;

pub fn vssm_allowed(_pre: &Prefiltered, _q: &Query) -> Allowed {
    Allowed::Within(0.0, 1.0)
}
pub fn mssm_allowed(_pre: &Prefiltered, _q: &Query) -> Allowed {
    Allowed::Within(0.0, 1.0)
}
pub fn hausdorff_allowed(_pre: &Prefiltered, _q: &Query) -> Allowed {
    Allowed::Within(0.0, 1.0)
}
