function [rootpath, datapath, mytestflag] = psinsenvi()
% calbench's harness (bench/drive/peer_psins.py): PSINS's environment function is written by its
% installer, which this headless run does not use. The toolbox root comes from the environment.
rootpath = [getenv('PSINS_ROOT') '/']; datapath = [rootpath 'data/']; mytestflag = 0;
end
