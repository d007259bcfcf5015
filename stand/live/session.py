"""One live session: the bus (or a scene played on a private virtual bus), the reader,
the run file, the decoded streams and the signals, owned by one context manager.

``stand record``, ``stand measure`` and ``stand balance`` all run through
:class:`LiveSession`.  Frames are decoded once, as they arrive
(the family's builder, :mod:`stand.solve.acquisition`); the run file is written as
they come; nothing is read back from it.  SIGINT and SIGTERM end the session
cleanly (also when SIGINT was ignored when the process started, as under
``nohup``): the run is kept and marked complete.  A family with a set-up
on the bus (CANopen: :mod:`stand.drivers.canopen.setup`) is set up before the session
reads (the dialogue stored in the run), started, and on a real bus clocked by the host
until it closes; a scene's modules (``modules``) answer that set-up on the private bus.
The measuring loop on it is :func:`stand.live.loop.measure_until_precise`.
"""

from __future__ import annotations

import json
import signal
import threading
import time
from collections.abc import Callable
from types import FrameType
from typing import Any

from stand.core import Diagnostic
from stand.drivers.bus import BusReader, describe_bus, open_bus, open_player_bus, play
from stand.drivers.family import FrameBuilder
from stand.drivers.runs.run_writer import RunWriter
from stand.errors import BusError
from stand.i18n.words import said
from stand.solve.acquisition import Acquired, default_acquisition
from stand.solve.pipeline import SOFTWARE


class LiveSession:
    """A bus or a scene, read live into a run file and decoded streams.

    Parameters
    ----------
    bus_kwargs
        ``can.Bus`` options (for a scene: a private virtual channel).
    run_path
        The run file to create (an existing file is refused).
    config_toml
        The configuration text stored in the run.
    scene_frames
        Frames of a simulated run to play in real time on the bus, or None.
    silence_timeout_s
        No frame for this long ends the session (:class:`BusTimeoutError`) [s].
    first_frame_s
        Before the first frame, the silence allowed instead [s] (None: the same).  A
        session that received nothing leaves no run file.
    run_attrs
        More text attributes stored in the run file (the influence matrix used).
    """

    def __init__(
        self,
        bus_kwargs: dict[str, Any],
        run_path: str,
        *,
        config_toml: str = "",
        scene_frames: Any = None,
        silence_timeout_s: float = 2.0,
        first_frame_s: float | None = None,
        run_attrs: dict[str, str] | None = None,
        acquisition: Acquired | None = None,
        modules: Any = None,
        on_play: Callable[[float], None] | None = None,
    ):
        acquisition = acquisition or default_acquisition()
        self._setup = acquisition.setup()
        if self._setup is not None and scene_frames is None:  # its clock frames are recorded
            bus_kwargs = {"receive_own_messages": True, **bus_kwargs}
        self.bus_kwargs = bus_kwargs
        self._modules = modules
        self._modules_bus: Any = None
        self._started = False
        self.run_path = run_path
        self.config_toml = config_toml
        self.run_attrs = {**acquisition.descriptions_attr(), **(run_attrs or {})}
        self.where = describe_bus(bus_kwargs)
        self.builder: FrameBuilder = acquisition.builder()
        """The family's decoder (:mod:`stand.solve.acquisition`)."""
        self.failure: BusError | None = None
        self.stop_signal: int | None = None
        self._scene_frames = scene_frames
        self._on_play = on_play
        self._timeout, self._first_frame_s = silence_timeout_s, first_frame_s
        self._stop_player = threading.Event()
        self._player: threading.Thread | None = None
        self._saved: dict[int, Any] = {}
        self._closed = False
        self._streams: Any = None
        self.start = time.monotonic()

    # -- context -------------------------------------------------------------------------
    def __enter__(self) -> LiveSession:

        self.writer = RunWriter(
            self.run_path,
            source=json.dumps(self.bus_kwargs, default=str),
            config_toml=self.config_toml,
            software=SOFTWARE,
            attrs=self.run_attrs,
        )
        try:
            self.bus = open_bus(self.bus_kwargs)
        except BusError:
            self.writer.discard()  # nothing was received: leave no empty run behind
            raise
        try:
            self._set_up_modules()
        except BusError:
            self._shut_modules()
            self.bus.shutdown()
            self.writer.discard()
            raise
        if self._scene_frames is not None:
            tx, stamps = open_player_bus(self.bus_kwargs)
            frames, stop, on_play = self._scene_frames, self._stop_player, self._on_play

            def player() -> None:
                start = time.monotonic()
                if on_play is not None and len(frames):  # the physics' time 0, on this clock
                    on_play(start - float(frames.t_s[0]))
                play(tx, frames, stop=stop, wire_stamps=stamps, start_s=start)
                tx.shutdown()

            self._player = threading.Thread(target=player, daemon=True)
        quiet = () if self._setup is None else self._setup.clock_ids
        self.reader = BusReader(self.bus, channel_info=self.where, silence_timeout_s=self._timeout,
                                first_frame_s=self._first_frame_s, quiet_ids=quiet)  # fmt: skip
        if self._setup is not None:
            try:
                self._setup.start(produce=self._scene_frames is None, channel=self.where)
            except BusError:
                self.reader.close()
                self._shut_modules()
                self.bus.shutdown()
                self.writer.discard()
                raise
        self._install_signals()
        if self._player is not None:
            self._player.start()
        self.start = time.monotonic()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _set_up_modules(self) -> None:
        """A scene's modules on their side of the bus; CANopen modules set up over SDO."""
        if self._modules is not None:
            self._modules_bus = open_bus(self.bus_kwargs)
            self._modules.attach(self._modules_bus)
        if self._setup is not None:
            steps = self._setup.configure(self.bus, self.where)
            self.writer.add_attrs({self._setup.attr: json.dumps(steps)})

    def _shut_modules(self) -> None:
        if self._setup is not None:
            self._setup.stop()
        if self._modules is not None:
            self._modules.detach()
        if self._modules_bus is not None:
            self._modules_bus.shutdown()
            self._modules_bus = None

    def _install_signals(self) -> None:
        if threading.current_thread() is not threading.main_thread():
            return  # signal handlers belong to the main thread; Ctrl-C then raises there

        def stop(signum: int, frame: FrameType | None) -> None:
            self.stop_signal = signum

        for sig in (signal.SIGINT, signal.SIGTERM):
            self._saved[sig] = signal.signal(sig, stop)

    def _restore_signals(self) -> None:
        for sig, handler in self._saved.items():
            signal.signal(sig, handler)
        self._saved.clear()

    # -- reading -------------------------------------------------------------------------
    @property
    def elapsed_s(self) -> float:
        """Time since the session started [s]."""
        return time.monotonic() - self.start

    @property
    def stopping(self) -> bool:
        """A signal asked to stop, or the bus failed."""
        return self.stop_signal is not None or self.failure is not None

    @property
    def frames_received(self) -> int:
        return int(self.reader.frames_received)

    def read(self, timeout_s: float = 0.1) -> int:
        """Take the frames that came (waiting up to ``timeout_s``); return how many.

        A bus failure is kept in :attr:`failure` (the frames before it are kept too).
        """
        try:
            block = self.reader.read_block(timeout_s)
        except BusError as exc:
            self.failure = exc
            return 0
        self.writer.append(block)
        self.builder.add(block)
        return len(block)

    def streams(self, *, strict_status: bool = False) -> Any:
        """The decoded streams of everything received so far."""
        return self.builder.streams(strict_status=strict_status)

    # -- closing -------------------------------------------------------------------------
    def close(self) -> Any:
        """Stop the source, keep what came while stopping, close the run file (idempotent).

        Returns the run's streams (None if nothing came).
        """
        if self._closed:
            return self._streams
        self._closed = True
        try:
            self._stop_player.set()
            self._shut_modules()
            self.reader.close()
            self.bus.shutdown()
            try:
                block = self.reader.read_block(0.0)
                self.writer.append(block)
                self.builder.add(block)
            except BusError:
                pass
            notes = []
            if self.reader.overruns:
                notes.append(
                    Diagnostic(
                        "host_overrun",
                        said(
                            "{n} frames dropped: the host did not keep up", n=self.reader.overruns
                        ),
                        float(self.reader.overruns),
                    )
                )
            if self.failure is not None:
                notes.append(Diagnostic("bus_error", str(self.failure)))
            self.writer.warn(notes)
            self._streams = self.streams() if self.builder.frames else None
            if self.reader.frames_received == 0:
                self.writer.discard()  # nothing came: no empty run left to block a retry
            else:
                self.writer.close(self._streams)
        finally:
            self._restore_signals()
        return self._streams
