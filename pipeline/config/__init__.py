"""params.yaml: its schema, its rules, its errors and the validated configuration the stages read.

The package's modules, in the order a file goes through them: :mod:`bogie.guarded_yaml` reads the YAML
(a key given twice refused), :mod:`~pipeline.config.schema` validates it against the pydantic models (their
distributions in :mod:`~pipeline.config.distributions`), :mod:`~pipeline.config.rules` checks the rules between
keys and the bounds on the costs, :mod:`~pipeline.config.errors` words every bad key as one line, and
:mod:`~pipeline.config.settings` converts the result to SI into the frozen dataclasses (:class:`Config`).

The stages import from here: ``from pipeline.config import Config, ConfigError, load_config``.
"""

from pipeline.config import settings
from pipeline.config.settings import *  # noqa: F403 - the public names of settings, listed once there

__all__ = settings.__all__
