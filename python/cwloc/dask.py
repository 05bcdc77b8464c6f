"""Batch localization on a Dask cluster (docs/python.md, "Many photos on a cluster").

Queries are independent and an index is read-only, so a batch is sharded photo by photo over
the cluster's workers. Each worker process opens (memory-maps) the index once, on its first
photo, and keeps it for every later batch; the index path must be readable on every worker
(a shared file system, or the same file copied to each node).

    from dask.distributed import Client
    import cwloc.dask
    client = Client("scheduler-host:8786")          # or Client(LocalCluster(n_workers=4))
    records = cwloc.dask.localize_many(client, "/shared/city.cwl", photo_paths, max_features=6000)

The records are cwloc-localize's JSON records (schemas/localization-result.schema.json) as
dicts, in the order of the photos; a photo that cannot be used gets cwloc-localize's error
record, {"name", "success": False, "error"}, and the others go on.
"""
import os
import threading
from typing import Any, Dict, List, Optional, Sequence, Union

import cwloc

_Photo = Union[str, os.PathLike, bytes]

# Per worker process: the opened indexes by path. Worker threads share them (a Localizer is
# thread-safe); the lock only guards opening.
_opened: Dict[str, "cwloc.Localizer"] = {}
_opening = threading.Lock()


def _localizer(index: str) -> "cwloc.Localizer":
    with _opening:
        localizer = _opened.get(index)
        if localizer is None:
            localizer = _opened[index] = cwloc.Localizer.open(index)
        return localizer


def _portable(camera: Any) -> Any:
    """A camera as plain data that pickles (a cwloc.Camera does not), for the trip to a worker."""
    if isinstance(camera, cwloc.Camera):
        return (camera.model, camera.width, camera.height, list(camera.params), camera.calibration)
    return camera


def localize_photo_record(index: str, photo: _Photo, name: str,
                          camera: Optional[Any] = None, **options: Any) -> Dict[str, Any]:
    """One photo's record, named `name`, by this process's Localizer of `index`. Bad input
    (a broken photo, an absurd option) is the record's error, as cwloc-localize writes it."""
    if isinstance(camera, tuple):
        camera = cwloc.Camera(*camera)
    try:
        record = _localizer(index).localize_photo(photo, camera=camera, **options).to_dict()
    except cwloc.Error as error:
        return {"name": name, "success": False, "error": str(error)}
    record["name"] = name
    return record


def _names(photos: Sequence[_Photo], names: Optional[Sequence[str]]) -> List[str]:
    if names is not None:
        if len(names) != len(photos):
            raise ValueError(f"names: {len(names)} names for {len(photos)} photos")
        return list(names)
    return [os.fspath(p) if isinstance(p, (str, os.PathLike)) else f"photo_{i}"
            for i, p in enumerate(photos)]


def _cameras(photos: Sequence[_Photo], camera: Any) -> List[Any]:
    if isinstance(camera, (list, tuple)):
        if len(camera) != len(photos):
            raise ValueError(f"camera: {len(camera)} cameras for {len(photos)} photos")
        return [_portable(c) for c in camera]
    return [_portable(camera)] * len(photos)


def localize_many(client: Any, index: Union[str, os.PathLike], photos: Sequence[_Photo],
                  camera: Any = None, names: Optional[Sequence[str]] = None,
                  **options: Any) -> List[Dict[str, Any]]:
    """Localizes every photo (a path readable on the workers, or the file's bytes) on the
    client's cluster and returns their JSON records in order.

    camera: None (the EXIF focal length as a prior, else estimated), one camera for all (a
    cwloc.Camera or hloc's "MODEL W H PARAMS" text), or a list with one per photo.
    names: the records' names; by default a path's text, or photo_I for bytes.
    options: as Localizer.localize_photo's (cwloc-localize's flags, '-' as '_'); an unknown
    one or a value out of range raises cwloc.InvalidArgumentError before any photo is sent.
    """
    cwloc.Options(**options)  # a bad option fails the call here, not every photo on the cluster
    index = os.fspath(index)
    if not os.path.isabs(index):
        index = os.path.abspath(index)  # workers may start elsewhere
    record_names = _names(photos, names)
    photos = [os.path.abspath(p) if isinstance(p, (str, os.PathLike)) else p for p in photos]
    futures = client.map(localize_photo_record, [index] * len(photos), photos, record_names,
                         _cameras(photos, camera), pure=False, **options)
    return client.gather(futures)
