# The presets: every number that `PRESET=quick|full` scales, defined once, here. The Python steps
# receive these values as arguments from the rules; none has its own copy: training/config.py's
# defaults are read from this file (for the PRESET of the environment, as make reads it). (The
# dataset's scene count is data-gen/generate.py's, selected by --preset $(PRESET), unless
# DATASET_COUNT names one.)
#
# quick is sized for a 2-core machine: `make reference noisy train eval` from a clean clone,
# release build included, within 45 minutes (docs/measurements.md).

PRESET ?= quick
ifeq ($(filter $(PRESET),quick full),)
$(error PRESET=$(PRESET): expected quick or full)
endif

# $(eval $(call lx_preset,NAME,QUICK,FULL)): NAME ?= the selected preset's value, so every one is
# also overridable on the command line (`make eval EVAL_DLE="100 1000"`).
lx_preset = $(1) ?= $(if $(filter full,$(PRESET)),$(3),$(2))

# Dataset (pipelines/dataset.mk): the number of generated scenes, empty for the preset's own
# (data-gen/generate.py's PRESETS; scene i is the same whatever the count, and its split too),
# image side in pixels (data-gen/generate.py --side; models/default.onnx was trained at 160);
# reference samples per pixel; noisy snapshot levels.
DATASET_COUNT ?=
$(eval $(call lx_preset,DATASET_SIDE,112,384))
$(eval $(call lx_preset,REF_SPP,1024,4096))
$(eval $(call lx_preset,NOISY_LEVELS,1 2 4 8 16 32 64 256 1024,1 2 4 8 16 32 64 256 1024))
# The denoiser's albedo and normal features average at least FEATURE_SPP samples per pixel
# (aov-write --min-samples): antialiased, as Intel Open Image Denoise recommends, for the levels
# below it (the emission feature keeps each level's own samples). 16 first hits per pixel cost
# about as much as 2 spp of trace; on the Cornell box at 1 spp they lift luxest's denoiser by
# 3.1 dB (4.6 with the antialiased emission it adds back) and OIDN by 1.6 dB, less at 2-8 spp
# (docs/measurements.md, *Antialiased features*).
$(eval $(call lx_preset,FEATURE_SPP,16,16))
# The second input family: double-local-estimate images (estimate image, seed NOISY_SEED) of the
# train and valid scenes at these light-path counts, denoised with the NOISY_MAX features.
$(eval $(call lx_preset,DATASET_DLE,100 300 1000,100 1000 10000))
# Extra noise realizations of the training scenes (make noisy; pipelines/dataset.mk): the levels
# NOISY_EXTRA_LEVELS (those among NOISY_LEVELS) rendered again with each seed of NOISY_EXTRA_SEEDS,
# about 0.4 s a 112² scene and seed. Eight (`NOISY_EXTRA_SEEDS="2 3 4 5 6 7 8 9"`) gave a 6000-step
# fine-tuning +0.07 dB on the 12 validation rooms at every level (docs/measurements.md, *More
# noise per room*). None by default: each seed adds half of a scene's inputs (6 of 12) to the
# training arrays (a 384² full-preset dataset: ~8.5 GB a seed, held in GPU memory by DeviceCrops),
# and the presets' documented results were trained without them.
$(eval $(call lx_preset,NOISY_EXTRA_SEEDS,,))
$(eval $(call lx_preset,NOISY_EXTRA_LEVELS,1 2 4 8 16 32,1 2 4 8 16 32))

# Training (make train, and train.py's defaults: training/config.py reads them here): steps of
# the one-cycle schedule, and the time budget in minutes (quick: 0.29 to 0.33 s a step on 2
# cores, so that 17 minutes are 3100 to 3500 steps; docs/measurements.md, *The quick pipeline
# with detail gates*).
$(eval $(call lx_preset,TRAIN_STEPS,3400,60000))
$(eval $(call lx_preset,TRAIN_MINUTES,17,600))
# TRAIN_SCHEDULE=time (the default) makes the one cycle span TRAIN_MINUTES, or TRAIN_STEPS if
# those come first (train.py --schedule): the learning rate anneals to its end whatever the
# machine's speed. With `steps` the cycle spans TRAIN_STEPS alone, and a run the time budget cuts
# short ends with its rate still high.
TRAIN_SCHEDULE ?= time
# TRAIN_LOSS: l1 (L1 + MS-SSIM of the log-transferred radiance) or psnr (minus the evaluation's
# PSNR per crop; training/loss.py). The committed default model was fine-tuned with psnr from a
# model trained with l1; psnr from scratch is unmeasured.
TRAIN_LOSS ?= l1

# Evaluation (pipelines/eval.mk): the Cornell-box reference spp and progressive run's last spp,
# double-local-estimate light paths on the Cornell box, light-tracing paths on the Cornell box
# (the baseline), double-local-estimate paths on the dataset's test scenes, and the
# sensor cases' path counts as a fraction of make validate's.
$(eval $(call lx_preset,EVAL_REF_SPP,4096,65536))
$(eval $(call lx_preset,EVAL_PROG_SPP,1024,8192))
$(eval $(call lx_preset,EVAL_DLE,100 300 1000 3000,100 300 1000 3000 10000 30000))
$(eval $(call lx_preset,EVAL_LT,1000000 4000000 16000000,1000000 4000000 16000000 64000000 256000000))
$(eval $(call lx_preset,EVAL_DATA_DLE,100 1000,100 1000 10000))
$(eval $(call lx_preset,EVAL_SENSOR_SCALE,0.25,1))
# The public interiors held out (pipelines/eval.mk (4)): pixels on the long side (short: 16:9),
# reference spp (seed REF_SEED), noisy snapshots, double-local-estimate light paths.
$(eval $(call lx_preset,EVAL_PUBLIC_LONG,256,512))
$(eval $(call lx_preset,EVAL_PUBLIC_SHORT,144,288))
$(eval $(call lx_preset,EVAL_PUBLIC_REF_SPP,1024,8192))
$(eval $(call lx_preset,EVAL_PUBLIC_SPP,1 2 4 8 16 32 64,1 2 4 8 16 32 64))
$(eval $(call lx_preset,EVAL_PUBLIC_DLE,100 300,100 300 1000))

# Benchmark at equal error (pipelines/bench.mk): reference spp; the timed runs' spp of path
# tracing, light paths of light tracing and of the double local estimate.
$(eval $(call lx_preset,BENCH_REF_SPP,4096,16384))
$(eval $(call lx_preset,BENCH_SPP,16 64 256,16 64 256 1024))
$(eval $(call lx_preset,BENCH_LT,1000000 4000000 16000000,1000000 4000000 16000000 64000000))
$(eval $(call lx_preset,BENCH_DLE,30 100 300 1000,30 100 300 1000 3000 10000))
$(eval $(call lx_preset,BENCH_DLE_MIS,10000,10000))
$(eval $(call lx_preset,BENCH_DLE_PLAIN,300 1000,300 1000 3000))
# make bench-edges: 10 times estimate image's default light paths; the reference's spp.
$(eval $(call lx_preset,BENCH_EDGE_PATHS,3000,3000))
$(eval $(call lx_preset,BENCH_EDGE_REF_SPP,1024,4096))

# Validation (pipelines/validate.mk): multiplier of every case's light paths.
$(eval $(call lx_preset,VALIDATE_SCALE,1,10))

# Singularity study (pipelines/singularity.mk): light paths per run, gather samples per sensor.
$(eval $(call lx_preset,SINGULARITY_PATHS,1000000,10000000))
$(eval $(call lx_preset,SINGULARITY_SAMPLES,200000,2000000))

# Seeds (docs/architecture.md, *Seeds*). A sample depends only on (seed, pixel, sample index), so
# a reference rendered with its noisy images' seed would contain their samples: references use
# their own seed, and preprocess.py refuses a pair whose luxest.seed values are equal.
NOISY_SEED := 1
REF_SEED := 1000001
