"""``asyncio``'s ``Task`` and ``TaskQueue`` in Python, keyed on the simulated clock.

The unix port's ``asyncio`` runs on the C module ``_asyncio``, whose ``TaskQueue.push`` without
a time and ``Task.cancel`` read the port's own millisecond counter, not ``time.ticks_ms``: a
task woken by I/O or cancelled (``asyncio.wait_for`` cancels its sleeping waiter) would be
scheduled on the wall clock while the scheduler runs on the ``World``'s clock, and never run.
``install(core)`` gives ``asyncio.core`` these two classes instead (the same interface as
MicroPython's pure-Python fallback for ports without ``_asyncio``: ``peek``, ``push(task,
key=None)``, ``pop``, ``remove``; a task's ``coro``, ``data``, ``state``, ``ph_key``,
``done``, ``cancel`` and the await protocol), so every time in the scheduler is the simulated
one. The queue is a list kept in time order, first in first out among equal times: the firmware
has tens of tasks, not thousands. Call it before ``asyncio.new_event_loop()``, which builds the
loop's queues from them.
"""

_core = None


def _ticks() -> int:
    return _core.ticks()  # type: ignore[attr-defined, no-any-return]


def _diff(a: int, b: int) -> int:
    return _core.ticks_diff(a, b)  # type: ignore[attr-defined, no-any-return]


class TaskQueue:
    def __init__(self) -> None:
        self.tasks: list = []  # type: ignore[type-arg]

    def peek(self) -> "Task | None":
        return self.tasks[0] if self.tasks else None

    def push(self, task: "Task", key: "int | None" = None) -> None:
        task.data = None  # queued: it waits on nothing (a cancel sets it after the push)
        task.ph_key = _ticks() if key is None else key
        tasks = self.tasks
        i = len(tasks)
        while i > 0 and _diff(tasks[i - 1].ph_key, task.ph_key) > 0:
            i -= 1
        tasks.insert(i, task)

    def pop(self) -> "Task":
        return self.tasks.pop(0)  # type: ignore[no-any-return]

    def remove(self, task: "Task") -> None:
        if task in self.tasks:
            self.tasks.remove(task)


# named as asyncio's Task, which it stands in for on the simulated clock (scripts/names.py)
class Task:
    def __init__(self, coro: object, globals: object = None) -> None:
        self.coro = coro
        self.data: object = None  # what it waits on, or the exception to throw into it
        self.state: object = True  # True running, a TaskQueue of waiters or a callback,
        # None finished and not awaited, False finished and awaited
        self.ph_key = 0

    def __iter__(self) -> "Task":
        if not self.state:
            self.state = False  # finished: awaited now
        elif self.state is True:
            self.state = TaskQueue()  # the tasks that wait for this one
        elif not isinstance(self.state, TaskQueue):
            raise RuntimeError("can't wait")
        return self

    __await__ = __iter__

    def __next__(self) -> None:
        if not self.state:
            if self.data is None:  # finished, its exception already handled
                raise _core.CancelledError  # type: ignore[attr-defined]
            raise self.data  # type: ignore[misc]  # StopIteration(result) or the exception
        self.state.push(_core.cur_task)  # type: ignore[attr-defined]
        _core.cur_task.data = self  # type: ignore[attr-defined]

    def send(self, value: object) -> None:
        self.__next__()

    def done(self) -> bool:
        return not self.state

    def cancel(self) -> bool:
        if not self.state:
            return False
        if self is _core.cur_task:  # type: ignore[attr-defined]
            raise RuntimeError("can't cancel self")
        task = self
        while isinstance(task.data, Task):  # waiting on another task: cancel that one
            task = task.data
        queue = _core._task_queue  # type: ignore[attr-defined]
        if hasattr(task.data, "remove"):  # on an event's or the I/O queue: run it now
            task.data.remove(task)
            queue.push(task)
        elif _diff(task.ph_key, _ticks()) > 0:  # asleep: wake it now
            queue.remove(task)
            queue.push(task)
        task.data = _core.CancelledError  # type: ignore[attr-defined]
        return True


def install(core: object) -> None:
    """Make ``core`` (``asyncio.core``) build its tasks and queues from these classes."""
    global _core
    _core = core
    core.Task = Task  # type: ignore[attr-defined]
    core.TaskQueue = TaskQueue  # type: ignore[attr-defined]
