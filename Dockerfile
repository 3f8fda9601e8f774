# One image for the API, the Dask scheduler and the Dask workers (docker-compose.yml).
FROM python:3.11-slim-bookworm
RUN apt-get update \
    && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
       libportaudio2 libsndfile1 \
    && rm -rf /var/lib/apt/lists/*
WORKDIR /opt/touchbench
COPY pyproject.toml README.md ./
COPY touchbench ./touchbench
COPY app ./app
COPY benchmark ./benchmark
COPY features ./features
COPY drivers ./drivers
# PyTorch's CPU build (the default Linux wheel on PyPI carries CUDA libraries of several GB).
RUN pip install --no-cache-dir --extra-index-url https://download.pytorch.org/whl/cpu '.[all]'
RUN useradd --create-home touchbench && mkdir -p /var/lib/touchbench \
    && chown touchbench /var/lib/touchbench
USER touchbench
WORKDIR /var/lib/touchbench
EXPOSE 8000 8001 8786
CMD ["touchbench", "--help"]
