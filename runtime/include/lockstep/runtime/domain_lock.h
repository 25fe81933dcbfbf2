#pragma once
// A DDS domain id that no other process on this machine holds through the same lock
// files: tests, Python tests and benchmarks run at once (also from other checkouts), and
// two simulations on one domain hear each other's ticks.

namespace lockstep {

// A domain in 1..200 locked by this process until it exits (an exclusive flock on
// <tmp>/lockstep-test-domain-<d>.lock; the kernel drops it with the process, also after a
// crash). Starts at a pid-derived offset so processes rarely contend; the same domain
// for every call in one process. Throws std::runtime_error when all 200 are held.
int LockFreeDdsDomain();

}  // namespace lockstep
