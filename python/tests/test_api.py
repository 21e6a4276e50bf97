"""The module's surface: every public name documented, heavy calls release the GIL."""
import sys
import threading
import time

import quadrix

PUBLIC_FUNCTIONS = ["read_cloud", "write_cloud", "register", "model", "load_model", "fit", "synth", "scenes",
                    "sensors", "config", "config_schema", "config_keys", "presets"]
PUBLIC_CLASSES = ["Cloud", "Model", "RegistrationResult"]


def test_every_public_name_is_documented():
    assert set(PUBLIC_FUNCTIONS + PUBLIC_CLASSES) <= set(dir(quadrix))
    assert len(quadrix.__doc__) > 200
    for name in PUBLIC_FUNCTIONS:
        documentation = getattr(quadrix, name).__doc__
        assert documentation and len(documentation.split("\n", 1)[-1].strip()) > 40, name
    for name in PUBLIC_CLASSES:
        cls = getattr(quadrix, name)
        assert cls.__doc__ and len(cls.__doc__) > 40, name
        for member, value in vars(cls).items():
            if not member.startswith("_"):
                assert value.__doc__ and len(value.__doc__) > 10, f"{name}.{member}"


def test_register_releases_the_gil(street):
    """While a thread registers, the calling thread keeps running Python code.

    The switch interval is raised to 100 s, so the interpreter never takes the GIL from a thread:
    the main thread only runs while the worker has released it, i.e. while register computes with
    the GIL released. Held instead, the main loop would tick once or twice in all."""
    pair = street["pairs"][0]
    source, target = street["clouds"][pair["source"]], street["clouds"][pair["target"]]
    results = []
    worker = threading.Thread(target=lambda: results.append(quadrix.register(source, target)))
    interval = sys.getswitchinterval()
    sys.setswitchinterval(100.0)
    try:
        ticks = 0
        worker.start()
        while worker.is_alive():
            ticks += 1
            time.sleep(0.001)  # gives the GIL up; returns only when the worker does not hold it
        worker.join()
    finally:
        sys.setswitchinterval(interval)
    assert results and results[0].status == "ok"
    assert ticks >= 10, ticks
