"""Compiled kernels: the chunks of each chain signature (models.kernels.chunks) built to shared
libraries by a build queue outside the serving process (service.kernels.queue), kept in a
size-bounded cache on disk (service.kernels.cache) and loaded where a run finds them."""

from flexmech.service.kernels.cache import compiled_for

__all__ = ["compiled_for"]
