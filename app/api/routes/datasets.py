"""Data sets: upload (ARFF or CSV), list, describe, download as ARFF, rename, delete."""

from __future__ import annotations

import contextlib
import queue
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Annotated

from fastapi import APIRouter, File, Form, Request, Response, UploadFile, status
from fastapi.responses import StreamingResponse

from touchbench.app.api.deps import PageDep, ServiceDep, StoreDep, paginate
from touchbench.app.api.downloads import attachment
from touchbench.app.api.uploads import form_request, save_upload
from touchbench.app.schemas.datasets import (
    DatasetDescription,
    DatasetList,
    DatasetSummary,
    ImportRequest,
    ImportResult,
    RenameRequest,
    RenameResult,
)
from touchbench.app.services.datasets import (
    delete_dataset,
    describe_dataset,
    export_dataset,
    find_dataset,
    import_file,
    rename_dataset,
)
from touchbench.app.services.listing import count_datasets, list_datasets
from touchbench.app.store.database import Store

router = APIRouter(prefix="/api/datasets", tags=["datasets"])


@router.post(
    "",
    status_code=status.HTTP_201_CREATED,
    response_model=ImportResult,
    responses={200: {"model": ImportResult, "description": "The content was stored before."}},
)
def upload(
    service: ServiceDep,
    response: Response,
    file: Annotated[UploadFile, File(description="An ARFF or CSV file.")],
    name: Annotated[str | None, Form()] = None,
    targets: Annotated[
        str | None,
        Form(
            max_length=2000,
            description="N first attributes, -N last ones, or comma-separated names "
            "(default: MEKA's -C header, else the last attribute).",
        ),
    ] = None,
    format: Annotated[str | None, Form(description="arff or csv (default: by the ending).")] = None,
    groups: Annotated[
        str | None, Form(description="The column naming each instance's group.")
    ] = None,
    ignore: Annotated[str | None, Form(description="Comma-separated columns to leave out.")] = None,
) -> ImportResult:
    """Import an uploaded file as a data set (what the CLI's import prints as JSON); nothing
    is stored if the file has an error."""
    service.settings.work_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=service.settings.work_dir) as folder:
        fields = {
            "name": name,
            "targets": targets,
            "format": format,
            "groups": groups,
            "ignore": ignore,
        }
        form_request(ImportRequest, file=Path(folder) / "upload", **fields)  # before saving
        path = save_upload(file, Path(folder), "upload.arff")
        request = form_request(ImportRequest, file=path, source_name=path.name, **fields)
        result = import_file(service.store, request)
    if not result.created:
        response.status_code = status.HTTP_200_OK
    return result


@router.get("", response_model=DatasetList)
def datasets(store: StoreDep, page: PageDep, request: Request, response: Response) -> DatasetList:
    """The data sets, oldest first, a page of at most 1,000 (``X-Total-Count`` says how
    many there are, ``Link`` where the next page is)."""
    paginate(request, response, page, count_datasets(store))
    return DatasetList(datasets=list_datasets(store, page=page))


@router.get("/{dataset}", response_model=DatasetDescription)
def dataset(dataset: str, store: StoreDep) -> DatasetDescription:
    """Schema, class distribution per target and missing values (``touchbench show``)."""
    return describe_dataset(store, dataset)


@router.get(
    "/{dataset}/arff",
    response_class=StreamingResponse,
    responses={200: {"content": {"text/plain": {}}}},
)
def arff(dataset: str, store: StoreDep) -> StreamingResponse:
    """The data set as ARFF (MEKA's -C header for several targets), streamed."""
    info = find_dataset(store, dataset)  # the 404 with the usual message
    return StreamingResponse(
        _arff_lines(store, dataset),
        media_type="text/plain; charset=utf-8",
        headers={"Content-Disposition": attachment(f"{info.name}.arff")},
    )


@router.post("/{dataset}/rename", response_model=RenameResult)
def rename(dataset: str, body: RenameRequest, store: StoreDep) -> RenameResult:
    return rename_dataset(store, dataset, body)


@router.delete("/{dataset}", response_model=DatasetSummary)
def remove(dataset: str, store: StoreDep) -> DatasetSummary:
    """Delete a data set with its runs (refused while a run on it is going)."""
    return delete_dataset(store, dataset)


class _Abandoned(Exception):  # noqa: N818 (the client went away)
    pass


def _arff_lines(store: Store, dataset: str) -> Iterator[bytes]:
    """The export in chunks of about 64 kB, written by a thread through a bounded queue, so
    that memory stays flat whatever the size and a client that goes away stops the export."""

    chunks: queue.Queue[bytes | None] = queue.Queue(maxsize=8)
    abandoned = threading.Event()

    class _Pipe:
        def __init__(self) -> None:
            self.parts: list[str] = []
            self.size = 0

        def write(self, text: str) -> int:
            self.parts.append(text)
            self.size += len(text)
            if self.size >= 1 << 16:
                self.flush()
            return len(text)

        def flush(self) -> None:
            if not self.parts:
                return
            chunk = "".join(self.parts).encode("utf-8")
            self.parts, self.size = [], 0
            while True:
                try:
                    chunks.put(chunk, timeout=1.0)
                    return
                except queue.Full:
                    if abandoned.is_set():
                        raise _Abandoned from None

    def produce() -> None:
        pipe = _Pipe()
        try:
            export_dataset(store, dataset, pipe)  # type: ignore[arg-type]
            pipe.flush()
        except _Abandoned:
            return
        finally:
            while not abandoned.is_set():
                with contextlib.suppress(queue.Full):
                    chunks.put(None, timeout=1.0)
                    break

    threading.Thread(target=produce, daemon=True, name="arff-export").start()
    try:
        while (chunk := chunks.get()) is not None:
            yield chunk
    finally:
        abandoned.set()
