% calbench's harness: PSINS's own demo on its FOG/MEMS vehicle drive, unchanged, headless (the shims
% of this folder replace the progress bar and the figures). Run by bench/drive/peer_psins.py.
root = getenv('PSINS_ROOT');
addpath(genpath([root '/base']));
addpath([root '/demos']);
addpath(fileparts(mfilename('fullpath')));
more off
test_align_transfer_fog_mems
