#pragma once
// A DDS domain id that no other process on this machine holds through the same lock
// files: tests, Python tests and benchmarks run at once (also from other checkouts), and
// two simulations on one domain hear each other's ticks.

#include <string>

namespace lockstep {

// A domain in 1..200 locked by this process until it exits (an exclusive flock on
// <tmp>/lockstep-test-domain-<d>.lock; the kernel drops it with the process, also after a
// crash). Starts at a pid-derived offset so processes rarely contend; the same domain
// for every call in one process. Throws std::runtime_error when all 200 are held.
int LockFreeDdsDomain();

// The simulation a `lockstep up` (or `lockstep serve`) runs on a DDS domain holds that
// domain on this host: an exclusive flock on <tmp>/lockstep-domain-<d>.lock, which says who
// holds it ("pid <pid>: <what>"). Two simulations on one domain hear each other's ticks,
// acks and commands, so a second one is refused: throws lockstep::InputError naming the
// domain and the holder. The returned descriptor keeps the lock until the process exits
// (close-on-exec: services it starts do not inherit it). Per host: simulations on other
// machines of one DDS network are not seen (give each its own domain, docs/deployment.md).
int HoldSimulationDomain(int domain, const std::string& what);

}  // namespace lockstep
