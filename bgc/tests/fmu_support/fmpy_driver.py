"""Drives a bgc FMU with FMPy and libcosim, the importers the FMU tests check against (run by
bgc/tests/fmu_fmpy.rs).

simulate FMU KIND STOP DT RTOL SCENARIO.json
    On a worker thread of 1 MiB of stack, simulates with FMPy's simulate_fmu (KIND ModelExchange: CVode;
    CoSimulation: the FMU's own integrator) and prints CSV: `time` and the outputs, every number in Python's round-trip form. SCENARIO holds
    {"inputs": [names], "rows": [[t, values...], ...], "start": {name: value}}; a step is two rows at one time.

libcosim FMU STOP DT SCENARIO.json
    The same with the Open Simulation Platform's libcosim (FMI 2.0 Co-Simulation), a second importer.

jacobian FMU SCENARIO.json
    On a worker thread of 1 MiB of stack, instantiates the Model Exchange interface (FMI 2.0 or 3.0), sets the
    states and inputs of SCENARIO ("start" and the first row) and prints JSON {"dd": ..., "fd": ...}: for each state and input (columns), the directional derivatives of
    the state derivatives and outputs (rows) from fmi2GetDirectionalDerivative, and the same by central
    differences of fmi2GetDerivatives and fmi2GetReal; and, as column indices, the dependencies ModelStructure
    lists for each row (null where it lists none, meaning every state and input).
"""
import ctypes
import atexit
import json
import shutil
import sys
import threading

import numpy as np
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Model
from fmpy.fmi3 import FMU3Model


def unzipped(fmu):
    """The FMU extracted to a directory of its own, removed when the driver exits."""
    directory = extract(fmu)
    atexit.register(shutil.rmtree, directory, ignore_errors=True)
    return directory


def on_worker_thread(function, *args):
    """Runs `function(*args)` on a thread of 1 MiB of stack, as importers run FMUs on worker threads (the main
    thread's 8 MiB would hide an FMU that keeps a large Jacobian on the stack), and re-raises what it raised."""
    threading.stack_size(1 << 20)
    outcome = {}

    def run():
        try:
            outcome["value"] = function(*args)
        except BaseException as e:  # noqa: BLE001 (re-raised on the calling thread)
            outcome["error"] = e

    worker = threading.Thread(target=run)
    worker.start()
    worker.join()
    if "error" in outcome:
        raise outcome["error"]
    return outcome.get("value")


def scenario(path):
    with open(path) as f:
        return json.load(f)


def simulate(fmu, kind, stop, dt, rtol, path):
    s = scenario(path)
    md = read_model_description(fmu)
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    # Every input in the table (those the scenario leaves out at 0, as `bgc simulate` holds them).
    names = s["inputs"]
    given = [v.name for v in md.modelVariables if v.causality == "input"]
    rows = s["rows"] or [[0.0]]
    columns = [[r[0] for r in rows]] + [
        [r[1 + names.index(n)] if n in names else 0.0 for r in rows] for n in given]
    signals = None
    if given:
        signals = np.array(list(zip(*columns)),
                           dtype=[("time", np.float64)] + [(n, np.float64) for n in given])
    result = simulate_fmu(fmu, fmi_type=kind, stop_time=float(stop), output_interval=float(dt),
                          relative_tolerance=float(rtol), input=signals, start_values=s["start"],
                          output=outputs)
    print(",".join(["time"] + outputs))
    for row in result:
        print(",".join(repr(float(v)) for v in row))


def jacobian(fmu, path):
    s = scenario(path)
    md = read_model_description(fmu)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    states = [v for v in md.modelVariables if v.derivative is not None]
    state_vrs = [v.derivative.valueReference for v in states]
    deriv_vrs = [v.valueReference for v in states]
    output_vrs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
    input_vrs = [v.valueReference for v in md.modelVariables if v.causality == "input"]
    fmi3 = md.fmiVersion.startswith("3")
    model = FMU3Model if fmi3 else FMU2Model
    m = model(guid=md.guid, unzipDirectory=unzipped(fmu),
              modelIdentifier=md.modelExchange.modelIdentifier, instanceName="jacobian")
    m.instantiate()
    if fmi3:
        m.enterInitializationMode(startTime=0.0)
        m.exitInitializationMode()
        m.updateDiscreteStates()
        get, put = m.getFloat64, m.setFloat64
    else:
        m.setupExperiment(startTime=0.0)
        m.enterInitializationMode()
        m.exitInitializationMode()
        m.newDiscreteStates()
        get, put = m.getReal, m.setReal
    m.enterContinuousTimeMode()
    nx = len(states)
    x0 = np.zeros(nx)
    for k, sv in enumerate(state_vrs):
        for name, value in s["start"].items():
            if vr[name] == sv:
                x0[k] = value
    row = s["rows"][0] if s["rows"] else []
    u0 = {vr[n]: v for n, v in zip(s["inputs"], row[1:])}
    u = np.array([u0.get(r, 0.0) for r in input_vrs])

    def evaluate(x, uu):
        xs = np.ascontiguousarray(x, dtype=np.float64)
        m.setContinuousStates(xs.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), nx)
        if input_vrs:
            put(input_vrs, list(uu))
        return np.array(get(deriv_vrs + output_vrs))

    unknowns = deriv_vrs + output_vrs
    dd, fd = [], []
    evaluate(x0, u)
    for col, known in enumerate(state_vrs + input_vrs):
        dd.append(m.getDirectionalDerivative(unknowns, [known], [1.0]))
        dx, du = np.zeros(nx), np.zeros(len(input_vrs))
        base = x0[col] if col < nx else u[col - nx]
        h = 1e-6 * max(abs(base), 1e-3)
        if col < nx:
            dx[col] = h
        else:
            du[col - nx] = h
        plus, minus = evaluate(x0 + dx, u + du), evaluate(x0 - dx, u - du)
        fd.append(list((plus - minus) / (2 * h)))
        evaluate(x0, u)
    m.terminate()
    m.freeInstance()
    # The ModelStructure dependencies of each row, as column indices (None: not listed, i.e. all).
    columns = state_vrs + input_vrs
    listed = {u.variable.valueReference: u.dependencies for u in md.derivatives + md.outputs}
    deps = []
    for r in unknowns:
        d = listed.get(r)
        deps.append(None if d is None else sorted(columns.index(v.valueReference) for v in d))
    print(json.dumps({"dd": dd, "fd": fd, "deps": deps}))


def interface(fmu):
    """Calls the C interface directly, against the standard's rules too, and prints JSON of what it answered."""
    md = read_model_description(fmu)
    ident = md.coSimulation.modelIdentifier
    lib = ctypes.CDLL(f"{unzipped(fmu)}/binaries/linux64/{ident}.so")
    messages = []
    LOGGER = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                              ctypes.c_char_p, ctypes.c_char_p)

    def log(env, name, status, category, fmt, arg):
        messages.append((status, (arg or b"").decode()))

    logger = LOGGER(log)

    class Callbacks(ctypes.Structure):
        _fields_ = [("logger", LOGGER), ("allocate", ctypes.c_void_p), ("free", ctypes.c_void_p),
                    ("step_finished", ctypes.c_void_p), ("env", ctypes.c_void_p)]

    callbacks = Callbacks(logger, None, None, None, None)
    lib.fmi2Instantiate.restype = ctypes.c_void_p
    lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p,
                                    ctypes.POINTER(Callbacks), ctypes.c_int, ctypes.c_int]
    for f in ["fmi2SetupExperiment", "fmi2EnterInitializationMode", "fmi2ExitInitializationMode",
              "fmi2DoStep", "fmi2GetReal", "fmi2SetReal", "fmi2Reset", "fmi2FreeInstance", "fmi2GetFMUstate",
              "fmi2SetFMUstate", "fmi2FreeFMUstate", "fmi2Terminate", "fmi2GetDerivatives"]:
        getattr(lib, f).argtypes = None
    vp = ctypes.c_void_p
    out = {}

    def new(name, guid):
        return lib.fmi2Instantiate(name, 1, guid, b"", ctypes.byref(callbacks), 0, 0)

    guid = md.guid.encode()
    out["wrong_guid_is_null"] = new(b"a", b"{00000000-0000-0000-0000-000000000000}") is None
    out["wrong_guid_logged"] = any(s == 3 and "GUID" in m for s, m in messages)
    out["null_name_is_null"] = new(None, guid) is None
    out["null_component"] = lib.fmi2EnterInitializationMode(vp(None))
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    outputs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
    inputs = [v.valueReference for v in md.modelVariables if v.causality == "input"]
    params = [v.valueReference for v in md.modelVariables if v.causality == "parameter"]
    a, b = vp(new(b"a", guid)), vp(new(b"b", guid))
    n = len(outputs)
    buf = (ctypes.c_double * n)()
    refs = (ctypes.c_uint * n)(*outputs)
    messages.clear()
    out["step_before_init"] = lib.fmi2DoStep(a, ctypes.c_double(0.0), ctypes.c_double(0.01), 1)
    out["step_before_init_logged"] = any(s == 3 and "fmi2DoStep" in m for s, m in messages)
    out["null_values"] = lib.fmi2GetReal(a, refs, ctypes.c_size_t(n), None)
    # Derivatives are a Model Exchange call, and readable only once initialisation has begun.
    nx = md.numberOfContinuousStates
    dx = (ctypes.c_double * max(nx, 1))()
    out["derivatives_of_co_simulation"] = lib.fmi2GetDerivatives(a, dx, ctypes.c_size_t(nx))
    me = vp(lib.fmi2Instantiate(b"me", 0, guid, b"", ctypes.byref(callbacks), 0, 0))
    out["derivatives_before_init"] = lib.fmi2GetDerivatives(me, dx, ctypes.c_size_t(nx))
    lib.fmi2EnterInitializationMode(me)
    out["derivatives_in_init"] = lib.fmi2GetDerivatives(me, dx, ctypes.c_size_t(nx))
    # A negative value for each parameter in turn, until one is refused: what the log says.
    messages.clear()
    for r in params:
        if lib.fmi2SetReal(me, (ctypes.c_uint * 1)(r), ctypes.c_size_t(1), (ctypes.c_double * 1)(-1.0)) != 0:
            break
    out["non_physical_logged"] = [m for s, m in messages if s == 3]
    lib.fmi2FreeInstance(me)
    for c in (a, b):
        lib.fmi2SetupExperiment(c, 1, ctypes.c_double(1e-8), ctypes.c_double(0.0), 0, ctypes.c_double(0.0))
        lib.fmi2EnterInitializationMode(c)
        lib.fmi2ExitInitializationMode(c)
    p = (ctypes.c_uint * 1)(params[0])
    out["param_after_init"] = lib.fmi2SetReal(a, p, ctypes.c_size_t(1), (ctypes.c_double * 1)(1.0))
    one = (ctypes.c_uint * 1)(inputs[0])
    lib.fmi2SetReal(a, one, ctypes.c_size_t(1), (ctypes.c_double * 1)(1.0))

    def run(c, t0, steps):
        for k in range(steps):
            status = lib.fmi2DoStep(c, ctypes.c_double(t0 + k * 0.01), ctypes.c_double(0.01), 1)
            if status != 0:
                return None
        lib.fmi2GetReal(c, refs, ctypes.c_size_t(n), buf)
        return list(buf)

    out["a"] = run(a, 0.0, 5)
    out["b"] = run(b, 0.0, 5)
    state = vp(None)
    out["get_state"] = lib.fmi2GetFMUstate(a, ctypes.byref(state))
    out["a_on"] = run(a, 0.05, 5)
    out["set_state"] = lib.fmi2SetFMUstate(a, state)
    out["a_again"] = run(a, 0.05, 5)
    lib.fmi2FreeFMUstate(a, ctypes.byref(state))
    out["reset"] = lib.fmi2Reset(a)
    for c in (a,):
        lib.fmi2SetupExperiment(c, 1, ctypes.c_double(1e-8), ctypes.c_double(0.0), 0, ctypes.c_double(0.0))
        lib.fmi2EnterInitializationMode(c)
        lib.fmi2ExitInitializationMode(c)
    out["after_reset"] = run(a, 0.0, 5)
    lib.fmi2FreeInstance(a)
    lib.fmi2FreeInstance(b)
    lib.fmi2FreeInstance(vp(None))
    print(json.dumps(out))


def interface3(fmu):
    """The FMI 3.0 interface called directly, against the standard's rules too; prints JSON of its answers."""
    md = read_model_description(fmu)
    lib = ctypes.CDLL(f"{unzipped(fmu)}/binaries/x86_64-linux/{md.coSimulation.modelIdentifier}.so")
    messages = []
    LOG = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p)
    log = LOG(lambda env, status, category, message: messages.append((status, message.decode())))
    b, d, vp = ctypes.c_bool, ctypes.c_double, ctypes.c_void_p
    lib.fmi3InstantiateCoSimulation.restype = vp
    lib.fmi3InstantiateCoSimulation.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, b, b, b, b,
                                                vp, ctypes.c_size_t, vp, LOG, vp]
    lib.fmi3DoStep.argtypes = [vp, d, d, b, ctypes.POINTER(b), ctypes.POINTER(b), ctypes.POINTER(b),
                               ctypes.POINTER(d)]
    lib.fmi3EnterInitializationMode.argtypes = [vp, b, d, d, b, d]
    lib.fmi3ExitInitializationMode.argtypes = [vp]
    lib.fmi3SetFloat64.argtypes = [vp, vp, ctypes.c_size_t, vp, ctypes.c_size_t]
    lib.fmi3GetFloat64.argtypes = [vp, vp, ctypes.c_size_t, vp, ctypes.c_size_t]
    lib.fmi3FreeInstance.argtypes = [vp]

    def new(token):
        return lib.fmi3InstantiateCoSimulation(b"a", token, None, False, False, False, False, None, 0, None,
                                               log, None)

    out = {"wrong_token_is_null": new(b"{0}") is None}
    out["wrong_token_logged"] = any(st == 3 and "instantiation token" in m for st, m in messages)
    c = new(md.guid.encode())
    flags = [b(), b(), b()]
    last = d(-1.0)

    def step(t):
        return lib.fmi3DoStep(c, t, 0.01, True, *(ctypes.byref(f) for f in flags), ctypes.byref(last))

    out["step_before_init"] = step(0.0)
    out["enter_init"] = lib.fmi3EnterInitializationMode(c, True, 1e-8, 0.0, False, 0.0)
    out["exit_init"] = lib.fmi3ExitInitializationMode(c)
    param = [v.valueReference for v in md.modelVariables if v.causality == "parameter"][0]
    vr = (ctypes.c_uint * 1)(param)
    value = (d * 2)(1.0, 2.0)
    out["param_after_init"] = lib.fmi3SetFloat64(c, vr, 1, value, 1)
    out["counts_differ"] = lib.fmi3GetFloat64(c, vr, 1, value, 2)
    out["step"] = step(0.0)
    out["last_successful_time"] = last.value
    lib.fmi3FreeInstance(c)
    print(json.dumps(out))


def libcosim(fmu, stop, dt, path):
    """The second importer: the Open Simulation Platform's libcosim (FMI 2.0 Co-Simulation) steps the FMU with
    the scenario's inputs, held over each communication step, and prints CSV like `simulate`."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    s = scenario(path)
    md = read_model_description(fmu)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    step_ns = round(float(dt) * 1e9)
    steps = round(float(stop) / float(dt))
    execution = CosimExecution.from_step_size(step_size=step_ns)
    index = execution.add_local_slave(local_slave=CosimLocalSlave(fmu_path=fmu, instance_name="plant"))
    for name, value in s["start"].items():
        execution.real_initial_value(slave_index=index, variable_reference=vr[name], value=value)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    manipulator = CosimManipulator.create_override()
    execution.add_manipulator(manipulator=manipulator)
    out_refs = [vr[n] for n in outputs]
    in_refs = [vr[n] for n in s["inputs"]]

    def inputs_at(t):
        # The value from t on: the last row at or before t (at a step, the row after the jump).
        row = [r for r in s["rows"] if r[0] <= t + 1e-12][-1]
        return row[1:]

    print(",".join(["time"] + outputs))
    for k in range(steps + 1):
        t = k * step_ns * 1e-9
        if in_refs:
            manipulator.slave_real_values(slave_index=index, variable_references=in_refs, values=inputs_at(t))
        if k == steps:
            break
        execution.step()
        y = observer.last_real_values(slave_index=index, variable_references=out_refs)
        print(",".join(repr(float(v)) for v in [(k + 1) * step_ns * 1e-9] + list(y)))


if __name__ == "__main__":
    if sys.argv[1] == "simulate":
        on_worker_thread(simulate, *sys.argv[2:8])
    elif sys.argv[1] == "interface":
        interface(sys.argv[2])
    elif sys.argv[1] == "libcosim":
        libcosim(*sys.argv[2:6])
    elif sys.argv[1] == "interface3":
        interface3(sys.argv[2])
    else:
        on_worker_thread(jacobian, *sys.argv[2:4])
