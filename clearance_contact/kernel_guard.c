/* The kernel library's argument guard in C (clearance_contact.kernel_library, "Safety").
 *
 * A Guard holds, for one kernel, the argument types of each exported version and the
 * export itself, and a fallback. Called, it passes the call to the first export whose
 * types every argument has (numba's typeof would give that exact type) and otherwise
 * (other types, another number of arguments, keywords) to the fallback: numba's
 * just-in-time dispatcher. About 10 ns an argument; checks written in Python cost ~150.
 * The descriptions are validated once, when the Guard is made (a malformed one raises).
 *
 * Argument descriptions (Python tuples, built by kernel_library.guard_spec):
 *   (KIND_FLOAT64,) (KIND_INT64,) (KIND_BOOL,)
 *   (KIND_ARRAY, dtype kind character, item size, ndim, required NPY_ARRAY_* flags)
 *   (KIND_TUPLE, description, description, ...)
 */
#define PY_SSIZE_T_CLEAN
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <Python.h>
#include <stddef.h>
#include <numpy/arrayobject.h>
#include <numpy/arrayscalars.h>

enum { KIND_FLOAT64 = 0, KIND_INT64 = 1, KIND_BOOL = 2, KIND_ARRAY = 3, KIND_TUPLE = 4 };

typedef struct {
    PyObject_HEAD
    PyObject *versions; /* tuple of (descriptions tuple, export) */
    PyObject *fallback;
    PyObject *dict;
    vectorcallfunc vectorcall;
} Guard;

static int matches(PyObject *value, PyObject *description)
{
    long kind = PyLong_AsLong(PyTuple_GET_ITEM(description, 0));
    switch (kind) {
    case KIND_FLOAT64:
        return PyFloat_Check(value);
    case KIND_INT64: {
        if (PyArray_IsScalar(value, Int64))
            return 1;
        if (!PyLong_CheckExact(value))
            return 0;
        int overflow = 0;
        PyLong_AsLongLongAndOverflow(value, &overflow);
        return overflow == 0;
    }
    case KIND_BOOL:
        return PyBool_Check(value) || PyArray_IsScalar(value, Bool);
    case KIND_ARRAY: {
        if (!PyArray_CheckExact(value))
            return 0;
        PyArrayObject *array = (PyArrayObject *)value;
        PyArray_Descr *dtype = PyArray_DESCR(array);
        long flags = PyLong_AsLong(PyTuple_GET_ITEM(description, 4));
        return dtype->kind == (char)PyLong_AsLong(PyTuple_GET_ITEM(description, 1))
            && PyArray_ITEMSIZE(array) == PyLong_AsLong(PyTuple_GET_ITEM(description, 2))
            && PyArray_ISNOTSWAPPED(array) && !PyDataType_HASFIELDS(dtype)
            && PyArray_NDIM(array) == PyLong_AsLong(PyTuple_GET_ITEM(description, 3))
            && (PyArray_FLAGS(array) & flags) == flags;
    }
    case KIND_TUPLE: {
        Py_ssize_t size = PyTuple_GET_SIZE(description) - 1;
        if (!PyTuple_CheckExact(value) || PyTuple_GET_SIZE(value) != size)
            return 0;
        for (Py_ssize_t k = 0; k < size; k++)
            if (!matches(PyTuple_GET_ITEM(value, k), PyTuple_GET_ITEM(description, k + 1)))
                return 0;
        return 1;
    }
    }
    return 0;
}

/* 1 if description is well formed (the layout above), else 0 with a ValueError set. */
static int valid_description(PyObject *description)
{
    if (!PyTuple_Check(description) || PyTuple_GET_SIZE(description) < 1 || !PyLong_CheckExact(PyTuple_GET_ITEM(description, 0))) {
        PyErr_Format(PyExc_ValueError, "an argument description is a tuple starting with an int kind, not %R", description);
        return 0;
    }
    long kind = PyLong_AsLong(PyTuple_GET_ITEM(description, 0));
    if (kind == -1 && PyErr_Occurred())
        return 0;
    Py_ssize_t size = PyTuple_GET_SIZE(description);
    if (kind == KIND_ARRAY) {
        for (Py_ssize_t k = 1; k < 5 && k < size; k++) {
            PyObject *field = PyTuple_GET_ITEM(description, k);
            if (!PyLong_CheckExact(field) || PyLong_AsLong(field) < 0)
                size = -1;
            if (PyErr_Occurred())
                return 0; /* an int too large for a C long: OverflowError */
        }
        if (size != 5) {
            PyErr_Format(PyExc_ValueError, "an array description is (kind, dtype kind, item size, ndim, flags) ints, not %R", description);
            return 0;
        }
        return 1;
    }
    if (kind == KIND_TUPLE) {
        for (Py_ssize_t k = 1; k < size; k++)
            if (!valid_description(PyTuple_GET_ITEM(description, k)))
                return 0;
        return 1;
    }
    if ((kind == KIND_FLOAT64 || kind == KIND_INT64 || kind == KIND_BOOL) && size == 1)
        return 1;
    PyErr_Format(PyExc_ValueError, "unknown argument description %R", description);
    return 0;
}

static PyObject *guard_vectorcall(PyObject *self, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    Guard *guard = (Guard *)self;
    Py_ssize_t nargs = PyVectorcall_NARGS(nargsf);
    if (guard->versions == NULL || guard->fallback == NULL) { /* cleared by the collector: never called then */
        PyErr_SetString(PyExc_RuntimeError, "kernel guard used after it was cleared");
        return NULL;
    }
    if (kwnames == NULL || PyTuple_GET_SIZE(kwnames) == 0) {
        Py_ssize_t count = PyTuple_GET_SIZE(guard->versions);
        for (Py_ssize_t v = 0; v < count; v++) {
            PyObject *version = PyTuple_GET_ITEM(guard->versions, v);
            PyObject *descriptions = PyTuple_GET_ITEM(version, 0);
            if (PyTuple_GET_SIZE(descriptions) != nargs)
                continue;
            Py_ssize_t k = 0;
            while (k < nargs && matches(args[k], PyTuple_GET_ITEM(descriptions, k)))
                k++;
            if (k == nargs)
                return PyObject_Vectorcall(PyTuple_GET_ITEM(version, 1), args, nargsf, NULL);
        }
    }
    /* a strong reference for the call: switch_to_numba replaces the fallback while the old one runs */
    PyObject *fallback = guard->fallback;
    Py_INCREF(fallback);
    PyObject *result = PyObject_Vectorcall(fallback, args, nargsf, kwnames);
    Py_DECREF(fallback);
    return result;
}

static PyObject *guard_new(PyTypeObject *type, PyObject *args, PyObject *kwargs)
{
    PyObject *versions, *fallback;
    if (!PyArg_ParseTuple(args, "O!O:Guard", &PyTuple_Type, &versions, &fallback))
        return NULL;
    for (Py_ssize_t v = 0; v < PyTuple_GET_SIZE(versions); v++) {
        PyObject *version = PyTuple_GET_ITEM(versions, v);
        if (!PyTuple_Check(version) || PyTuple_GET_SIZE(version) != 2 || !PyTuple_Check(PyTuple_GET_ITEM(version, 0))
            || !PyCallable_Check(PyTuple_GET_ITEM(version, 1))) {
            PyErr_Format(PyExc_ValueError, "a version is (descriptions tuple, export callable), not %R", version);
            return NULL;
        }
        PyObject *descriptions = PyTuple_GET_ITEM(version, 0);
        for (Py_ssize_t k = 0; k < PyTuple_GET_SIZE(descriptions); k++)
            if (!valid_description(PyTuple_GET_ITEM(descriptions, k)))
                return NULL;
    }
    if (!PyCallable_Check(fallback)) {
        PyErr_SetString(PyExc_TypeError, "the fallback must be callable");
        return NULL;
    }
    Guard *guard = (Guard *)type->tp_alloc(type, 0);
    if (guard == NULL)
        return NULL;
    Py_INCREF(versions);
    Py_INCREF(fallback);
    guard->versions = versions;
    guard->fallback = fallback;
    guard->dict = NULL;
    guard->vectorcall = guard_vectorcall;
    return (PyObject *)guard;
}

static int guard_traverse(Guard *guard, visitproc visit, void *arg)
{
    Py_VISIT(guard->versions);
    Py_VISIT(guard->fallback);
    Py_VISIT(guard->dict);
    return 0;
}

static int guard_clear(Guard *guard)
{
    Py_CLEAR(guard->versions);
    Py_CLEAR(guard->fallback);
    Py_CLEAR(guard->dict);
    return 0;
}

static void guard_dealloc(Guard *guard)
{
    PyObject_GC_UnTrack(guard);
    guard_clear(guard);
    Py_TYPE(guard)->tp_free((PyObject *)guard);
}

static PyObject *guard_get_fallback(Guard *guard, void *closure)
{
    Py_INCREF(guard->fallback);
    return guard->fallback;
}

static int guard_set_fallback(Guard *guard, PyObject *value, void *closure)
{
    if (value == NULL || !PyCallable_Check(value)) {
        PyErr_SetString(PyExc_TypeError, "the fallback must be callable");
        return -1;
    }
    Py_INCREF(value);
    Py_SETREF(guard->fallback, value);
    return 0;
}

static PyGetSetDef guard_getset[] = {
    {"__dict__", PyObject_GenericGetDict, PyObject_GenericSetDict, NULL, NULL},
    {"fallback", (getter)guard_get_fallback, (setter)guard_set_fallback, "what a call no export takes goes to", NULL},
    {NULL},
};

static PyTypeObject GuardType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "kernel_guard.Guard",
    .tp_basicsize = sizeof(Guard),
    .tp_dealloc = (destructor)guard_dealloc,
    .tp_vectorcall_offset = offsetof(Guard, vectorcall),
    .tp_call = PyVectorcall_Call,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_doc = "Guard(versions, fallback): call the first export whose argument types match, else fallback.",
    .tp_traverse = (traverseproc)guard_traverse,
    .tp_clear = (inquiry)guard_clear,
    .tp_getset = guard_getset,
    .tp_dictoffset = offsetof(Guard, dict),
    .tp_new = guard_new,
};

static PyObject *check(PyObject *module, PyObject *args)
{
    PyObject *value, *description;
    if (!PyArg_ParseTuple(args, "OO:check", &value, &description) || !valid_description(description))
        return NULL;
    return PyBool_FromLong(matches(value, description));
}

static PyMethodDef methods[] = {
    {"check", check, METH_VARARGS, "check(value, description) -> bool: what a Guard decides for one argument"},
    {NULL},
};

static struct PyModuleDef module_definition = {PyModuleDef_HEAD_INIT, "kernel_guard", NULL, -1, methods};

PyMODINIT_FUNC PyInit_kernel_guard(void)
{
    import_array();
    if (PyType_Ready(&GuardType) < 0)
        return NULL;
    PyObject *module = PyModule_Create(&module_definition);
    if (module == NULL)
        return NULL;
    Py_INCREF(&GuardType);
    if (PyModule_AddObject(module, "Guard", (PyObject *)&GuardType) < 0) {
        Py_DECREF(&GuardType);
        Py_DECREF(module);
        return NULL;
    }
    return module;
}
