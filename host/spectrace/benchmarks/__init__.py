"""`spectrace bench` and its modes: the plain throughput run (`render.py`), the side-by-side comparison with
Mitsuba 3, equal-time quality, closest-hit rays/s against Embree, scaling tables, cold kernel builds, the samplers'
error and the kernel shapes. Peers (Mitsuba, Embree) come from the `bench` extra and are imported only by the modes
that need them."""
