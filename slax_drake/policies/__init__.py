"""Search policies: the :class:`~slax_drake.policies.protocol.Policy` protocol, DAR, DER-k, Bluction-DAR, the
oracles and the project's own (hindsight, belief), and the registry that builds them by name. They plan with the
action model of :mod:`slax_drake.shelf`.

The names below are imported from their submodule on first use (:mod:`slax_drake.lazy_exports`)."""

from slax_drake.lazy_exports import lazy_exports

_EXPORTS = {
    "Decision": "protocol", "Policy": "protocol",
    "POLICY_NAMES": "registry", "make_policy": "registry",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
