"""The deadline rush for Locust (benches/rush.sh runs it): each user is one student who,
as a browser does, opens /register and registers with the invite code, logs in with the
key it was shown, opens the submission form and uploads an original-task robot.py,
waits until the version is ready, and plays two practice matches with the button on
its page, waiting for each to end; then it stops.

Settings come from the environment:
  RUSH_CODE        the invite code
  RUSH_COMPETITION the competition's name
  RUSH_ROBOT       the robot.py to upload
  RUSH_ADDRESSES   the client addresses to connect from, in turn (e.g. 127.0.0.2,127.0.0.3;
                   empty: the system's choice)

Besides the requests (named by route), it reports as request type RUSH:
  "upload to ready"   the time from the upload's answer to the version's `ready`;
  "refused right key" a 429 answer to a request that proved who it was (must not happen);
  "lost upload"       an upload answered 303 whose version never appeared or never got
                      ready (must not happen);
  "stopped"           a student who could not go on (an answer that was not the one a
                      browser expects: its step and HTTP status, in the failures).
"""

import itertools
import os
import re
import threading
import time

import gevent
import requests.adapters
from locust import HttpUser, constant, events, task
from locust.exception import StopUser

CODE = os.environ["RUSH_CODE"]
COMPETITION = os.environ["RUSH_COMPETITION"]
ROBOT = open(os.environ["RUSH_ROBOT"], "rb").read()
ADDRESSES = [a for a in os.environ.get("RUSH_ADDRESSES", "").split(",") if a]
NUMBERS = itertools.count()
LOCK = threading.Lock()


@events.test_start.add_listener
def stop_when_everyone_is_done(environment, **_):
    """Ends the run once every student has taken part (each user stops itself)."""

    def watch():
        gevent.sleep(5)
        while environment.runner.user_count > 0:
            gevent.sleep(1)
        environment.runner.quit()

    gevent.spawn(watch)


class FromAddress(requests.adapters.HTTPAdapter):
    """Connections from one local address: one of several clients on this machine."""

    def __init__(self, address, **kwargs):
        self.address = address
        super().__init__(**kwargs)

    def init_poolmanager(self, *args, **kwargs):
        kwargs["source_address"] = (self.address, 0)
        super().init_poolmanager(*args, **kwargs)


def csrf(page):
    m = re.search(r'name="csrf" value="([^"]+)"', page)
    return m.group(1) if m else None


class Student(HttpUser):
    # Each user acts at once and once: the journey is the whole task.
    wait_time = constant(0)

    def on_start(self):
        with LOCK:
            self.number = next(NUMBERS)
        if ADDRESSES:
            adapter = FromAddress(ADDRESSES[self.number % len(ADDRESSES)])
            self.client.mount("http://", adapter)

    def report(self, name, started, failure=None):
        self.environment.events.request.fire(
            request_type="RUSH",
            name=name,
            response_time=(time.time() - started) * 1000,
            response_length=0,
            exception=failure,
            context={},
        )

    def refused(self, what):
        self.report("refused right key", time.time(), Exception(what))

    def stopped(self, what, response=None):
        """Reports why this student stops before the end, and stops it."""
        status = getattr(response, "status_code", None)
        self.report("stopped", time.time(), Exception(f"{what}: HTTP {status}"))
        raise StopUser()

    def lost(self, what):
        self.report("lost upload", time.time(), Exception(what))

    def checked(self, response, what):
        if response.status_code == 429:
            self.refused(what)
        return response

    @task
    def take_part(self):
        name = f"student-{self.number}"
        self.client.get("/register", name="GET /register")
        r = self.checked(
            self.client.post(
                "/register",
                data={"name": name, "invite_code": CODE},
                name="POST /register",
            ),
            "registration with the right code",
        )
        m = re.search(r'id="new-key">([0-9a-f]+)<', r.text)
        if r.status_code != 200 or not m:
            self.stopped("registration", r)
        key = m.group(1)
        r = self.checked(
            self.client.post(
                "/login", data={"key": key}, allow_redirects=False, name="POST /login"
            ),
            "login with the right key",
        )
        if r.status_code != 303:
            self.stopped("login", r)
        r = self.checked(
            self.client.get(
                f"/competitions/{COMPETITION}/submit", name="GET /competitions/[c]/submit"
            ),
            "the submission form",
        )
        token = csrf(r.text)
        if not token:
            self.stopped("the submission form", r)
        r = self.checked(
            self.client.post(
                f"/competitions/{COMPETITION}/submit",
                data={"csrf": token, "name": f"robot-{self.number}", "original_task": "true"},
                files={"files": ("robot.py", ROBOT)},
                allow_redirects=False,
                name="POST /competitions/[c]/submit",
            ),
            "the upload",
        )
        if r.status_code != 303:
            self.stopped("the upload", r)
        uploaded = time.time()
        headers = {"authorization": f"Bearer {key}"}
        me = self.client.get("/api/me", headers=headers, name="GET /api/me").json()
        if not me.get("bots"):
            self.lost("no bot after the upload")
            raise StopUser()
        bot = me["bots"][0]["bot_id"]
        while True:
            v = self.client.get(
                f"/api/bots/{bot}", headers=headers, name="GET /api/bots/[id] (waiting)"
            ).json()
            status = v["versions"][0]["build_status"]
            if status == "ready":
                break
            if status != "building" or time.time() - uploaded > 1800:
                self.lost(f"the version ended {status}")
                raise StopUser()
            time.sleep(0.5)
        self.report("upload to ready", uploaded)
        matches = []
        for _ in range(2):
            page = self.client.get("/me", name="GET /me").text
            token = csrf(page)
            maze = re.search(r'name="maze_id"[^>]*>\s*<option value="(\d+)"', page)
            if not token or not maze:
                self.stopped("the practice button", None)
            r = self.checked(
                self.client.post(
                    "/me/practice",
                    data={"csrf": token, "bot_id": bot, "maze_id": maze.group(1)},
                    allow_redirects=False,
                    name="POST /me/practice",
                ),
                "practice",
            )
            location = r.headers.get("location", "")
            if r.status_code != 303 or not location.startswith("/matches/"):
                self.stopped("practice", r)
            matches.append(location.rsplit("/", 1)[1])
        for match in matches:
            while True:
                v = self.client.get(
                    f"/api/matches/{match}", name="GET /api/matches/[id] (waiting)"
                ).json()
                if v["status"] not in ("queued", "running"):
                    break
                time.sleep(1)
        raise StopUser()
