"""pnp: the pick-and-place platform from Python.

- pnp.Platform(endpoints): train runs and watch them, read metrics and checkpoints, promote,
  and play live episodes on the inference service (Platform.session()).
- pnp.PickAndPlaceEnv(sim_address, robot=, object=, world=, seed=): one simulation-service
  environment with the Gymnasium goal-environment API (registered as pnp/PickAndPlace-v0
  when gymnasium is installed).
- pnp.VectorPickAndPlaceEnv(n, ...): n environments, one RPC per step for all of them.

Errors from a service are pnp.PlatformError, carrying the gRPC status code and the
server's message; bad arguments are ValueError naming the argument and what it expects; a
reply of the wrong shape (a server of another version) is pnp.ReplyError.
"""

from pnp import _dependencies

_dependencies.ensure()

from pnp.endpoints import Endpoints  # noqa: E402  (after the dependencies are found)
from pnp.env import PickAndPlaceEnv  # noqa: E402
from pnp.errors import PlatformError, ReplyError  # noqa: E402
from pnp.platform import Platform, Run  # noqa: E402
from pnp.session import Prediction, Session  # noqa: E402
from pnp.vector_env import VectorPickAndPlaceEnv  # noqa: E402

__all__ = ["Endpoints", "PickAndPlaceEnv", "PlatformError", "Platform", "Prediction", "ReplyError",
           "Run", "Session", "VectorPickAndPlaceEnv"]
__version__ = "0.1.0"
