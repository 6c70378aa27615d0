// The body-against-body phase of stepBodies. Private to the runtime.
#pragma once

#include <bspf/movement.h>

#include <span>

namespace bspf::detail {

/// Pushes overlapping bodies apart, each by half the overlap, horizontally
/// (see stepBodies); each push is a move against the level. Adds the pushes'
/// contacts and body contacts to `reports` (empty, or parallel to `bodies`).
void pushBodiesApart(const World& world, std::span<Body> bodies, StepScratch& scratch,
                     std::span<StepReport> reports);

}  // namespace bspf::detail
