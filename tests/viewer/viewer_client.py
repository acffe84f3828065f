"""A client of the viewer's HTTP API for the tests: plain http.client, so that the headers a browser would send
(Origin, Host, Sec-Fetch-Site) can be set or forged."""

from __future__ import annotations

import http.client
import json
import time
from urllib.parse import urlsplit

from spectrace.resources import scenes_dir
from spectrace.scene import load_scene


def small_scene(name: str = "cornell_box.toml", width: int = 32, height: int = 24, spp: int = 4):
    return load_scene(scenes_dir() / name).with_overrides(width=width, height=height, spp=spp)


class Client:
    def __init__(self, url: str):
        parts = urlsplit(url)
        self.host, self.port = parts.hostname, parts.port
        self.token = parts.query.removeprefix("token=")

    def request(
        self, method: str, path: str, body: object = None, headers: dict | None = None, token: bool = True
    ) -> tuple[int, bytes, dict]:
        connection = http.client.HTTPConnection(self.host, self.port, timeout=60)
        if token:
            path += ("&" if "?" in path else "?") + f"token={self.token}"
        data = body if isinstance(body, bytes) else (json.dumps(body).encode() if body is not None else None)
        sent = {"Content-Type": "application/json"} if data is not None else {}
        sent.update(headers or {})
        try:
            connection.request(method, path, body=data, headers=sent)
            reply = connection.getresponse()
            return reply.status, reply.read(), dict(reply.getheaders())
        finally:
            connection.close()

    def get_json(self, path: str) -> dict:
        status, body, _ = self.request("GET", path)
        assert status == 200, body
        return json.loads(body)

    def post(self, path: str, body: object) -> tuple[int, dict]:
        status, reply, _ = self.request("POST", path, body)
        return status, json.loads(reply)

    def state(self) -> dict:
        return self.get_json("/api/state")

    def wait_for(self, condition, timeout: float = 120.0) -> dict:
        end = time.monotonic() + timeout
        while True:
            state = self.state()
            if condition(state):
                return state
            assert time.monotonic() < end, f"timed out; last state {state}"
            time.sleep(0.05)

    def wait_done(self, timeout: float = 120.0) -> dict:
        return self.wait_for(lambda s: s["spp"] >= s["target_spp"] and s["spp"] > 0, timeout)
