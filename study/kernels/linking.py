"""Helpers compiled for linking only: optimized and turned into machine code once, inside the kernel that calls them.

numba gives every compiled function its own code library and *finalizes* it on its own: it links in the libraries
of the functions it calls, optimizes the whole (LLVM's module passes) and generates its machine code. A helper that
only compiled code calls needs neither: its caller links the helper's code into its own library and optimizes and
generates it again there. So along a chain of helpers (the loop -> the event location -> the right-hand side -> the
friction solve) the code at the bottom was optimized and generated once per level above it: on a cold cache the
compiled loop's closure (about 20 functions) took about 30 s of LLVM work, mostly that repetition.

:func:`link_only` compiles a function whose library is finalized for linking only: the function passes numba runs
on each function as it is lowered (as before), its callees linked in, and nothing else: no module passes, no machine
code, nothing on disk (a helper's compiled form is only its LLVM module, which an entry kernel's cache entry
contains). The kernel that calls it (a :func:`study.kernels.cache.kernel` with a cache entry and machine code)
optimizes its whole closure once with numba's full pipeline and generates it once. Without fast-math the
optimizations keep every floating-point operation as written (no reassociation, no contraction), so the results
are those of the helpers finalized one by one, bit for bit.

The library class and the pipeline pass use numba's compiler internals (``CPUCodeLibrary``, the pass manager):
requirements.lock pins the numba they are written for, and the compiled-path tests run every kernel through them.
"""

from __future__ import annotations

from numba import njit, types
from numba.core.codegen import JITCodeLibrary
from numba.core.compiler import CompilerBase, DefaultPassBuilder
from numba.core.compiler_lock import require_global_compiler_lock
from numba.core.compiler_machinery import LoweringPass, register_pass
from numba.core.typed_passes import AnnotateTypes


class LinkOnlyLibrary(JITCodeLibrary):
    """A code library finalized for linking into its callers only (see the module docstring)."""

    def finalize(self):
        require_global_compiler_lock()
        self._raise_if_finalized()
        seen = set()
        for library in self._linking_libraries:
            if library not in seen:
                seen.add(library)
                self._reload_init.update(library._reload_init)
                self._final_module.link_in(library._get_module_for_linking(), preserve=True)
        self._final_module.verify()
        self._finalize_dynamic_globals()
        self._finalized = True

    def get_pointer_to_function(self, name):
        """No machine code: numba asks for the (absent) Python wrapper's address, which is null for these."""
        self._ensure_finalized()
        return 0

    @property
    def codegen(self):
        """The codegen as numba's lowering sees it (``get_executable`` sets the function's environment through it):
        with no machine code there is no environment variable to set."""
        return _NoEnvironment(self._codegen)


class _NoEnvironment:
    """A codegen whose ``set_env`` does nothing (see :attr:`LinkOnlyLibrary.codegen`); everything else is the
    codegen's."""

    def __init__(self, codegen):
        self._codegen = codegen

    def set_env(self, env_name, env):
        pass

    def __getattr__(self, name):
        return getattr(self._codegen, name)


@register_pass(mutates_CFG=False, analysis_only=False)
class _UseLinkOnlyLibrary(LoweringPass):
    """Give the function a :class:`LinkOnlyLibrary` before numba's lowering would create an ordinary one."""

    _name = "study_link_only_library"

    def __init__(self):
        LoweringPass.__init__(self)

    def run_pass(self, state):
        state.library = LinkOnlyLibrary(state.targetctx.codegen(), state.func_id.func_qualname)
        return True


class _LinkOnlyPipeline(CompilerBase):
    """numba's nopython pipeline with :class:`_UseLinkOnlyLibrary` before the lowering."""

    def define_pipelines(self):
        pm = DefaultPassBuilder.define_nopython_pipeline(self.state)
        pm.add_pass_after(_UseLinkOnlyLibrary, AnnotateTypes)
        pm.finalize()
        return [pm]


def link_only(func):
    """``numba.njit`` for a function that only compiled code calls, finalized for linking only (module docstring):
    no Python or C wrapper, no disk cache, no machine code of its own.

    A constant argument (``stages(..., 1, 4, ...)``) is typed as its plain type, not as a literal: numba would
    otherwise compile the function once more for each literal value (the steppers' ``stages`` three times)."""
    dispatcher = njit(no_cpython_wrapper=True, no_cfunc_wrapper=True, pipeline_class=_LinkOnlyPipeline)(func)
    typed = dispatcher.get_call_template

    def get_call_template(args, kws):
        return typed(tuple(types.unliteral(a) for a in args), {k: types.unliteral(v) for k, v in kws.items()})
    dispatcher.get_call_template = get_call_template
    return dispatcher
