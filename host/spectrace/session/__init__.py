"""A live render session: a scene built once on a device, then rendered pass by pass and edited in place by the key
paths of its scene file (docs/python-api.md, "Live sessions")."""

from spectrace.session.session import Session, UpdateReport, UpdateStep

__all__ = ["Session", "UpdateReport", "UpdateStep"]
