#pragma once
// Eigen and a namespace-scope `using namespace SimTK;` do not mix: SimTKcommon declares
// catch-all comparison templates (template <class L, class R> bool operator!=(const L&,
// const R&)); once the using-directive is in scope they win over the built-in comparison of
// Eigen's enum constants in constant expressions, are not constexpr, and Eigen fails with pages
// of errors: where the directive precedes Eigen's headers, and (with GCC 12) also where it
// follows them but Eigen's templates are instantiated after it (e.g. Eigen::Vector2d(1, 2)).
// Every flatsos header that includes Eigen includes this one first, so that in the first case
// the first error points here.
// IF THE static_assert BELOW FAILS TO COMPILE: a `using namespace SimTK;` comes before this
// #include. In files that use flatsos' Eigen-based API (models, planner), write
// using-declarations (`using SimTK::Vec3;`), a block-scope `using namespace SimTK;`, or qualify
// SimTK's names. The muscle headers (flatsos/muscles/*, flatsos/plugin/force/*, the integrators)
// include no Eigen and work with the directive anywhere.

namespace flatsos::detail {
enum SimtkNamespaceProbe { kSimtkNamespaceProbe = 1 };
static_assert(kSimtkNamespaceProbe != 0, "`using namespace SimTK;` before a flatsos header that includes Eigen");
}  // namespace flatsos::detail
