"""`spectrace bench` modes beyond the plain throughput run (spectrace.bench): the side-by-side comparison with
Mitsuba 3, equal-time quality, closest-hit rays/s against Embree, scaling tables and cold kernel builds.
Peers (Mitsuba, Embree) come from the `bench` extra and are imported only by the modes that need them."""
